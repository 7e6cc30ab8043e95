#include "symb/io/stdio_stream.hpp"

#include <unistd.h>

namespace symb::io {

StdioStream::StdioStream() : StdioStream("stdio", STDIN_FILENO, STDOUT_FILENO) {}

StdioStream::StdioStream(const std::string& name, int in_fd, int out_fd)
    : Device(name),
      FdStream(name),
      in_fd_(in_fd),
      out_fd_(out_fd),
      in_tty_(::isatty(in_fd) == 1),
      out_tty_(::isatty(out_fd) == 1) {
  add_ioctl({"info", std::nullopt, "descriptors and whether each is a terminal"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              std::string out = "in_fd=" + std::to_string(in_fd_) + " in_tty=" + (in_tty_ ? "true" : "false") +
                                " out_fd=" + std::to_string(out_fd_) + " out_tty=" + (out_tty_ ? "true" : "false") +
                                " open=" + (is_open() ? "true" : "false");
              if (const std::string why = failure(); !why.empty()) out += " failure=\"" + why + "\"";
              return out;
            });
  (void)open();  // a bad descriptor leaves the stream closed; open() says why when asked
}

kernel::Status StdioStream::open() {
  if (is_open()) return {};
  close();  // after end of input the descriptors are still attached
  return attach(in_fd_, out_fd_, false);
}

}  // namespace symb::io
