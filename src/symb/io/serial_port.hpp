// SerialPort: a serial line through the POSIX terminal interface (termios), the paper's
// UARTIOStream. The same class drives a USB-serial adapter (/dev/ttyUSB0), a board's UART
// (/dev/ttyS0) and a pseudo-terminal (the simulator link without hardware): all are terminals to
// the kernel, so nothing here depends on which one it is. The line runs in raw mode by default
// (every byte 0..255 passes untouched: no echo, no line editing, no CR/LF translation, no
// XON/XOFF), because frames and shell text both need the bytes as sent.
//
// ioctls: "baud" (int, 9600..4000000, one of the rates termios has a constant for), "parity"
// (none|even|odd; a pseudo-terminal has no parity bit and says so in the answer), "raw" (bool; false gives back the
// settings the terminal had when opened, with baud and parity applied), "flush" (drops unread input and unsent output),
// "info" (settings, and the device's own view of them read back with tcgetattr).
#pragma once

#include <termios.h>

#include <memory>
#include <mutex>
#include <span>
#include <string>

#include "symb/io/fd_stream.hpp"
#include "symb/kernel/result.hpp"

namespace symb::io {

enum class Parity { kNone, kEven, kOdd };
const char* to_string(Parity p);

struct SerialSettings {
  int baud = 115200;
  Parity parity = Parity::kNone;
  bool raw = true;
};

class SerialPort : public FdStream {
 public:
  // A port on a device path; open() opens it and applies `settings`. The ioctls work before
  // open() too: the settings are kept and applied when the port opens.
  SerialPort(const std::string& name, std::string path, SerialSettings settings = {});
  // Takes an open terminal descriptor (a pseudo-terminal master) and applies `settings`. Such a
  // port cannot be opened again after close(), as nothing names its device.
  static kernel::Result<std::unique_ptr<SerialPort>> adopt(const std::string& name, int fd, std::string label,
                                                           SerialSettings settings = {});

  kernel::Status open() override;
  const std::string& path() const { return path_; }
  SerialSettings settings() const;
  // Every baud rate the "baud" ioctl accepts, ascending.
  static std::span<const int> supported_bauds();

 private:
  SerialPort(const std::string& name, std::string path, SerialSettings settings, bool reopenable);
  void add_ioctls();
  // Applies `s` to the open descriptor; checks the device kept the speed.
  kernel::Status apply(int fd, const SerialSettings& s);
  // Changes one setting: kept for the next open(), applied now when open; undone if refused.
  kernel::Result<std::string> change(SerialSettings s);
  std::string info();
  // Empty when the open device kept `s`'s parity; otherwise a note saying what it has instead.
  std::string kept_note(const SerialSettings& s);

  std::string path_;
  bool reopenable_;
  mutable std::mutex settings_mu_;  // settings_ and original_ (the shell may call ioctl anytime)
  SerialSettings settings_;
  termios original_{};  // as found at open, for raw = false
  bool have_original_ = false;
};

}  // namespace symb::io
