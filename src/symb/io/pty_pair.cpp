#include "symb/io/pty_pair.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace symb::io {

kernel::Result<PtyPair> PtyPair::open(const std::string& name, SerialSettings settings) {
  const int master_fd = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_fd < 0) return kernel::Error{"pty '" + name + "': posix_openpt failed: " + std::strerror(errno)};
  char path[128] = {};
  if (::grantpt(master_fd) != 0 || ::unlockpt(master_fd) != 0 || ::ptsname_r(master_fd, path, sizeof path) != 0) {
    const int e = errno;
    ::close(master_fd);
    return kernel::Error{"pty '" + name + "': cannot unlock the slave: " + std::strerror(e)};
  }
  PtyPair pair;
  pair.slave_path = path;
  // The slave is opened first: it is configured (raw, no echo) before the master can send a byte
  // that the terminal layer would otherwise echo or translate.
  pair.slave = std::make_shared<SerialPort>(name + ".slave", pair.slave_path, settings);
  if (auto st = pair.slave->open(); !st) {
    ::close(master_fd);
    return kernel::Error{"pty '" + name + "': " + st.error()};
  }
  auto master = SerialPort::adopt(name + ".master", master_fd, "pty master of " + pair.slave_path, settings);
  if (!master) return kernel::Error{"pty '" + name + "': " + master.error()};
  pair.master = std::move(master).value();
  return pair;
}

}  // namespace symb::io
