// Streams: devices that move bytes (the paper's InputStream, OutputStream and IOStream). A
// driver implements read_some() and write_all(); the stream classes add the C++ stream operators
// the paper asks for, so a value is written or read in one line with the conversion done for the
// user: `out << 42 << ' ' << 1.5 << '\n'`, `in >> n >> x`. Text is the conversion format (what a
// terminal or a shell expects); binary data travels as bytes or, framed, through FrameCodec.
//
// Thread use: one reader and one writer at a time may use a stream concurrently (a reader thread
// and a task that writes), as with a file descriptor; close() may be called from any thread and
// wakes a blocked reader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "symb/io/device.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::io {

class InputDevice : public virtual Device {
 public:
  using Device::Device;
  // Reads what is available, at most buf.size() bytes, waiting up to `timeout` for the first
  // byte. Returns 0 on timeout; an error on end of stream (peer closed) or a failure, after
  // which is_open() is false.
  virtual kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) = 0;
};

class OutputDevice : public virtual Device {
 public:
  using Device::Device;
  // Writes all of `data` or fails (the device is then closed or broken).
  virtual kernel::Status write_all(std::span<const std::byte> data) = 0;
};

class InputStream : public InputDevice {
 public:
  using InputDevice::InputDevice;

  // Text extraction: skips white space, reads one token and converts it. On a timeout (see
  // set_read_timeout) or a token that does not convert, the stream's fail flag is set and the
  // target is left unchanged, as with std::istream.
  InputStream& operator>>(std::string& token);
  InputStream& operator>>(std::int64_t& v);
  InputStream& operator>>(int& v);
  InputStream& operator>>(double& v);
  InputStream& operator>>(float& v);
  InputStream& operator>>(bool& v);
  // Reads up to and without the next '\n' (a '\r' before it is dropped). Nothing on timeout:
  // what was read so far is kept for the next call. Lines longer than max_length are cut.
  kernel::Result<std::optional<std::string>> read_line(kernel::Duration timeout, std::size_t max_length = 4096);

  bool fail() const { return fail_; }
  void clear_fail() { fail_ = false; }
  explicit operator bool() const { return !fail_; }
  void set_read_timeout(kernel::Duration t) { read_timeout_ = t; }

 private:
  bool peek_byte(std::byte& b, kernel::Duration timeout);
  bool next_token(std::string& token);

  std::byte buffer_[256]{};
  std::size_t buffered_ = 0;
  std::size_t pos_ = 0;
  std::string partial_line_;
  bool fail_ = false;
  kernel::Duration read_timeout_ = std::chrono::seconds(1);
};

class OutputStream : public OutputDevice {
 public:
  using OutputDevice::OutputDevice;

  // Text insertion: numbers in their shortest exact text form, strings as they are. A failed
  // write sets the fail flag.
  OutputStream& operator<<(std::string_view s);
  OutputStream& operator<<(const char* s) { return *this << std::string_view(s); }
  OutputStream& operator<<(char c) { return *this << std::string_view(&c, 1); }
  OutputStream& operator<<(std::int64_t v);
  OutputStream& operator<<(int v) { return *this << static_cast<std::int64_t>(v); }
  OutputStream& operator<<(std::uint64_t v);
  OutputStream& operator<<(double v);
  OutputStream& operator<<(float v);
  OutputStream& operator<<(bool v) { return *this << (v ? "true" : "false"); }
  // Raw bytes, unconverted.
  OutputStream& operator<<(std::span<const std::byte> bytes);

  bool fail() const { return fail_; }
  void clear_fail() { fail_ = false; }
  explicit operator bool() const { return !fail_; }

 private:
  bool fail_ = false;
};

class IOStream : public InputStream, public OutputStream {
 public:
  explicit IOStream(std::string name) : Device(std::move(name)), InputStream(""), OutputStream("") {}
  // One stream, one state: failure on either side shows, and clearing clears both.
  bool fail() const { return InputStream::fail() || OutputStream::fail(); }
  void clear_fail() {
    InputStream::clear_fail();
    OutputStream::clear_fail();
  }
  using InputStream::operator>>;
  using OutputStream::operator<<;
  explicit operator bool() const { return !InputStream::fail() && !OutputStream::fail(); }
};

// Bytes as a std::span, for the many places that hold text.
inline std::span<const std::byte> as_bytes(std::string_view s) {
  return {reinterpret_cast<const std::byte*>(s.data()), s.size()};
}

}  // namespace symb::io
