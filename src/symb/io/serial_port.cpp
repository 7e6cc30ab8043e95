#include "symb/io/serial_port.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <string_view>

namespace symb::io {

namespace {

struct BaudRate {
  int rate;
  speed_t constant;
};

// termios names speeds by constants, not numbers; only these exist (Linux has the high ones).
constexpr BaudRate kBauds[] = {
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
    {115200, B115200},   {230400, B230400},
#ifdef B460800
    {460800, B460800},   {500000, B500000},   {576000, B576000},   {921600, B921600},
    {1000000, B1000000}, {1152000, B1152000}, {1500000, B1500000}, {2000000, B2000000},
    {2500000, B2500000}, {3000000, B3000000}, {3500000, B3500000}, {4000000, B4000000},
#endif
};

constexpr auto kBaudList = [] {
  std::array<int, std::size(kBauds)> a{};
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = kBauds[i].rate;
  return a;
}();

const BaudRate* find_baud(std::int64_t rate) {
  for (const auto& b : kBauds)
    if (b.rate == rate) return &b;
  return nullptr;
}

int rate_of(speed_t constant) {
  for (const auto& b : kBauds)
    if (b.constant == constant) return b.rate;
  return 0;
}

std::string supported_text() {
  std::string s;
  for (const auto& b : kBauds) {
    if (!s.empty()) s += ' ';
    s += std::to_string(b.rate);
  }
  return s;
}

}  // namespace

const char* to_string(Parity p) {
  switch (p) {
    case Parity::kNone: return "none";
    case Parity::kEven: return "even";
    case Parity::kOdd: return "odd";
  }
  return "?";
}

std::span<const int> SerialPort::supported_bauds() { return kBaudList; }

SerialPort::SerialPort(const std::string& name, std::string path, SerialSettings settings)
    : SerialPort(name, std::move(path), settings, true) {}

SerialPort::SerialPort(const std::string& name, std::string path, SerialSettings settings, bool reopenable)
    : Device(name), FdStream(name), path_(std::move(path)), reopenable_(reopenable), settings_(settings) {
  add_ioctls();
}

kernel::Result<std::unique_ptr<SerialPort>> SerialPort::adopt(const std::string& name, int fd, std::string label,
                                                              SerialSettings settings) {
  if (find_baud(settings.baud) == nullptr)
    return kernel::Error{"serial port '" + name + "': unsupported baud rate " + std::to_string(settings.baud)};
  std::unique_ptr<SerialPort> port(new SerialPort(name, std::move(label), settings, false));
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    const int e = errno;
    ::close(fd);
    return kernel::Error{"serial port '" + port->name() + "': not a terminal: " + std::strerror(e)};
  }
  port->original_ = t;
  port->have_original_ = true;
  if (auto st = port->apply(fd, settings); !st) {
    ::close(fd);
    return kernel::Error{st.error()};
  }
  if (auto st = port->attach(fd, fd, true); !st) {
    ::close(fd);
    return kernel::Error{st.error()};
  }
  return port;
}

SerialSettings SerialPort::settings() const {
  std::lock_guard lock(settings_mu_);
  return settings_;
}

kernel::Status SerialPort::open() {
  if (is_open()) return {};
  if (!reopenable_) return kernel::Error{"serial port '" + name() + "' (" + path_ + ") cannot be opened again"};
  close();  // a port that failed (the device went away) still holds its descriptor
  // O_NONBLOCK: opening a real port must not wait for a modem's carrier; O_NOCTTY: a robot's
  // serial line must never become this process's controlling terminal.
  const int fd = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return kernel::Error{"serial port '" + name() + "': cannot open " + path_ + ": " + std::strerror(errno)};
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    const int e = errno;
    ::close(fd);
    return kernel::Error{"serial port '" + name() + "': " + path_ + " is not a terminal: " + std::strerror(e)};
  }
  SerialSettings s;
  {
    std::lock_guard lock(settings_mu_);
    original_ = t;
    have_original_ = true;
    s = settings_;
  }
  if (auto st = apply(fd, s); !st) {
    ::close(fd);
    return st;
  }
  if (auto st = attach(fd, fd, true); !st) {
    ::close(fd);
    return st;
  }
  return {};
}

kernel::Status SerialPort::apply(int fd, const SerialSettings& s) {
  const BaudRate* baud = find_baud(s.baud);
  if (baud == nullptr)
    return kernel::Error{"serial port '" + name() + "': unsupported baud rate " + std::to_string(s.baud)};
  termios t{};
  {
    std::lock_guard lock(settings_mu_);
    if (!s.raw && have_original_)
      t = original_;
    else if (::tcgetattr(fd, &t) != 0)
      return kernel::Error{"serial port '" + name() + "': tcgetattr failed: " + std::strerror(errno)};
  }
  if (s.raw) cfmakeraw(&t);
  // CLOCAL: ignore modem lines (most robot links have none); CREAD: let the receiver run.
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(PARENB | PARODD);
  t.c_iflag &= ~static_cast<tcflag_t>(INPCK | IGNPAR | PARMRK);
  if (s.parity != Parity::kNone) {
    t.c_cflag |= PARENB;
    if (s.parity == Parity::kOdd) t.c_cflag |= PARODD;
    // A byte with a parity error is dropped; the frame it was in then fails its CRC.
    t.c_iflag |= INPCK | IGNPAR;
  }
  if (::cfsetispeed(&t, baud->constant) != 0 || ::cfsetospeed(&t, baud->constant) != 0)
    return kernel::Error{"serial port '" + name() + "': baud rate " + std::to_string(s.baud) + " refused"};
  if (::tcsetattr(fd, TCSANOW, &t) != 0)
    return kernel::Error{"serial port '" + name() + "': tcsetattr failed: " + std::strerror(errno)};
  // tcsetattr succeeds when any of the changes took; read back to catch a refused speed.
  termios back{};
  if (::tcgetattr(fd, &back) == 0 && ::cfgetospeed(&back) != baud->constant)
    return kernel::Error{"serial port '" + name() + "': device refused baud rate " + std::to_string(s.baud)};
  return {};
}

std::string SerialPort::kept_note(const SerialSettings& s) {
  std::string note;
  (void)with_fd([&](const WakeableFd::Use& u) -> kernel::Status {
    termios t{};
    if (::tcgetattr(u.read_fd(), &t) != 0) return {};
    // A pseudo-terminal has no parity bit: Linux clears PARENB on it whatever is asked. Say so
    // rather than fail, so the same settings serve a real line and its pseudo-terminal stand-in.
    const bool on = (t.c_cflag & PARENB) != 0;
    const bool odd = (t.c_cflag & PARODD) != 0;
    if (on != (s.parity != Parity::kNone) || (on && odd != (s.parity == Parity::kOdd)))
      note = std::string(" (not kept by the device, which has parity=") + (!on ? "none" : odd ? "odd" : "even") + ")";
    return {};
  });
  return note;
}

kernel::Result<std::string> SerialPort::change(SerialSettings s) {
  SerialSettings before;
  {
    std::lock_guard lock(settings_mu_);
    before = settings_;
    settings_ = s;
  }
  if (is_open()) {
    auto st = with_fd([&](const WakeableFd::Use& u) { return apply(u.read_fd(), s); });
    if (!st) {
      std::lock_guard lock(settings_mu_);
      settings_ = before;
      return kernel::Error{st.error()};
    }
  }
  return std::string("ok");
}

std::string SerialPort::info() {
  const SerialSettings s = settings();
  std::string out = "path=" + path_ + " open=" + (is_open() ? "true" : "false") + " baud=" + std::to_string(s.baud) +
                    " parity=" + to_string(s.parity) + " raw=" + (s.raw ? "true" : "false");
  (void)with_fd([&](const WakeableFd::Use& u) -> kernel::Status {
    termios t{};
    if (::tcgetattr(u.read_fd(), &t) != 0) {
      out += " device: tcgetattr failed: ";
      out += std::strerror(errno);
      return {};
    }
    const char* parity = (t.c_cflag & PARENB) == 0 ? "none" : (t.c_cflag & PARODD) != 0 ? "odd" : "even";
    const int bits = (t.c_cflag & CSIZE) == CS8   ? 8
                     : (t.c_cflag & CSIZE) == CS7 ? 7
                     : (t.c_cflag & CSIZE) == CS6 ? 6
                                                  : 5;
    out += " device: ispeed=" + std::to_string(rate_of(::cfgetispeed(&t))) +
           " ospeed=" + std::to_string(rate_of(::cfgetospeed(&t))) + " bits=" + std::to_string(bits) +
           " parity=" + parity + " canonical=" + ((t.c_lflag & ICANON) != 0 ? "true" : "false") +
           " echo=" + ((t.c_lflag & ECHO) != 0 ? "true" : "false");
    return {};
  });
  return out;
}

void SerialPort::add_ioctls() {
  add_ioctl({"baud",
             os::ParamSpec{"baud", os::ParamType::kInt, std::int64_t{115200}, 9600.0, 4000000.0, "line speed in bit/s"},
             "sets the line speed; one of " + supported_text()},
            [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
              const auto rate = std::get<std::int64_t>(*arg);
              if (find_baud(rate) == nullptr)
                return kernel::Error{"ioctl 'baud' of device '" + name() + "': unsupported baud rate " +
                                     std::to_string(rate) + " (supported: " + supported_text() + ")"};
              SerialSettings s = settings();
              s.baud = static_cast<int>(rate);
              auto r = change(s);
              if (!r) return r;
              return std::to_string(rate);
            });
  add_ioctl(
      {"parity",
       os::ParamSpec{"parity", os::ParamType::kString, std::string("none"), std::nullopt, 4.0, "none, even or odd"},
       "sets the parity bit: none, even or odd"},
      [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
        const auto& text = std::get<std::string>(*arg);
        SerialSettings s = settings();
        if (text == "none")
          s.parity = Parity::kNone;
        else if (text == "even")
          s.parity = Parity::kEven;
        else if (text == "odd")
          s.parity = Parity::kOdd;
        else
          return kernel::Error{"ioctl 'parity' of device '" + name() + "': '" + text.substr(0, 16) +
                               "' is not none, even or odd"};
        auto r = change(s);
        if (!r) return r;
        return std::string(to_string(s.parity)) + kept_note(s);
      });
  add_ioctl({"raw", os::ParamSpec{"raw", os::ParamType::kBool, true, std::nullopt, std::nullopt, "raw mode"},
             "true: every byte passes untouched; false: the terminal's settings as found at open"},
            [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
              SerialSettings s = settings();
              s.raw = std::get<bool>(*arg);
              auto r = change(s);
              if (!r) return r;
              return std::string(s.raw ? "true" : "false");
            });
  add_ioctl({"flush", std::nullopt, "drops unread input and unsent output"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              auto st = with_fd([&](const WakeableFd::Use& u) -> kernel::Status {
                if (::tcflush(u.read_fd(), TCIOFLUSH) != 0)
                  return kernel::Error{"serial port '" + name() + "': tcflush failed: " + std::strerror(errno)};
                return {};
              });
              if (!st) return kernel::Error{st.error()};
              return std::string("flushed");
            });
  add_ioctl({"info", std::nullopt, "settings, and the device's own view of them"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> { return info(); });
}

}  // namespace symb::io
