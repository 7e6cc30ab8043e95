// StdioStream: the process's standard input and output as one IOStream, so a command shell, a
// board's log or a test harness can run over a terminal or a pipe exactly as over a serial line.
// The descriptors are borrowed, never owned: close() lets go of them without closing them (the
// process keeps its stdin and stdout) and wakes a reader blocked on input. Their blocking mode is
// left alone, since it is shared with whatever else holds the same terminal or pipe.
#pragma once

#include <string>

#include "symb/io/fd_stream.hpp"

namespace symb::io {

class StdioStream final : public FdStream {
 public:
  // Standard input (fd 0) and standard output (fd 1), named "stdio"; open on return.
  StdioStream();
  // Any two descriptors (a pipe's ends, a terminal), borrowed; open on return (unless they are
  // not valid descriptors: then open() reports why).
  StdioStream(const std::string& name, int in_fd, int out_fd);

  // Attaches the descriptors again after close().
  kernel::Status open() override;
  bool input_is_tty() const { return in_tty_; }
  bool output_is_tty() const { return out_tty_; }

 private:
  int in_fd_;
  int out_fd_;
  bool in_tty_;
  bool out_tty_;
};

}  // namespace symb::io
