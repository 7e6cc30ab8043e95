// PtyPair: a pseudo-terminal, i.e. a serial cable inside the kernel. What is written to one end is
// read at the other, through the same terminal layer (termios, baud, parity, raw mode) a real UART
// goes through, so a simulator and a board process can talk as over RS-232 without hardware, and
// tests exercise the real serial driver (SerialPort) rather than an in-memory stand-in.
//
// The master end is the controlling side (a simulator, `symb link`); the slave end has a path
// (/dev/pts/N) that any program can open as a serial port. Keep `slave` open even when another
// program uses the path: while no slave descriptor is open the kernel reports the line as hung up
// and the master reads end of stream.
#pragma once

#include <memory>
#include <string>

#include "symb/io/serial_port.hpp"
#include "symb/kernel/result.hpp"

namespace symb::io {

struct PtyPair {
  std::shared_ptr<SerialPort> master;  // named `<name>.master`
  std::shared_ptr<SerialPort> slave;   // named `<name>.slave`, a SerialPort on slave_path
  std::string slave_path;

  // Opens a new pseudo-terminal (posix_openpt, grantpt, unlockpt) with both ends open and
  // configured with `settings` (raw mode by default, so every byte passes untouched).
  static kernel::Result<PtyPair> open(const std::string& name, SerialSettings settings = {});
};

}  // namespace symb::io
