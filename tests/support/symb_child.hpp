// A `symb` command run as a child process by the tests that need several programs at once (the
// hardware-in-the-loop pair over pseudo-terminals): `symb args` through /bin/sh, its stdout and
// stderr in a log file. The destructor kills a child that was not waited for.
#pragma once

#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

namespace symb::test_support {

// The whole file, or empty when it cannot be read.
inline std::string read_whole_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class SymbChild {
 public:
  SymbChild(const std::string& symb_binary, const std::string& args, std::filesystem::path log) : log_(std::move(log)) {
    const std::string command = "exec '" + symb_binary + "' " + args + " > '" + log_.string() + "' 2>&1";
    pid_ = ::fork();
    if (pid_ == 0) {
      ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~SymbChild() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      wait();
    }
  }
  SymbChild(const SymbChild&) = delete;
  SymbChild& operator=(const SymbChild&) = delete;

  // Ctrl-C, as a person would stop it.
  void interrupt() const { ::kill(pid_, SIGINT); }
  // Its exit status, or -1 when a signal ended it.
  int wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    done_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string output() const { return read_whole_file(log_); }

 private:
  std::filesystem::path log_;
  pid_t pid_ = -1;
  bool done_ = false;
};

}  // namespace symb::test_support
