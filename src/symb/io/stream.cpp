#include "symb/io/stream.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

namespace symb::io {

bool InputStream::peek_byte(std::byte& b, kernel::Duration timeout) {
  if (pos_ == buffered_) {
    auto n = read_some(buffer_, timeout);
    if (!n || *n == 0) return false;
    buffered_ = *n;
    pos_ = 0;
  }
  b = buffer_[pos_];
  return true;
}

bool InputStream::next_token(std::string& token) {
  token.clear();
  std::byte b{};
  for (;;) {
    if (!peek_byte(b, read_timeout_)) return false;
    if (!std::isspace(static_cast<unsigned char>(b))) break;
    ++pos_;
  }
  // A token ends at white space, or when nothing more comes within the read timeout.
  while (peek_byte(b, read_timeout_) && !std::isspace(static_cast<unsigned char>(b))) {
    if (token.size() >= 1024) return false;  // no number or word is that long: refuse, don't grow
    token.push_back(static_cast<char>(b));
    ++pos_;
  }
  return true;
}

namespace {
template <class T>
bool convert(const std::string& s, T& out) {
  T v{};
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc{} || r.ptr != s.data() + s.size()) return false;
  if constexpr (std::is_floating_point_v<T>)
    if (!std::isfinite(v)) return false;
  out = v;
  return true;
}
}  // namespace

InputStream& InputStream::operator>>(std::string& token) {
  std::string t;
  if (fail_ || !next_token(t))
    fail_ = true;
  else
    token = std::move(t);
  return *this;
}

#define SYMB_EXTRACT(T)                                          \
  InputStream& InputStream::operator>>(T& v) {                   \
    std::string t;                                               \
    if (fail_ || !next_token(t) || !convert(t, v)) fail_ = true; \
    return *this;                                                \
  }
SYMB_EXTRACT(std::int64_t)
SYMB_EXTRACT(int)
SYMB_EXTRACT(double)
SYMB_EXTRACT(float)
#undef SYMB_EXTRACT

InputStream& InputStream::operator>>(bool& v) {
  std::string t;
  if (fail_ || !next_token(t))
    fail_ = true;
  else if (t == "true" || t == "1")
    v = true;
  else if (t == "false" || t == "0")
    v = false;
  else
    fail_ = true;
  return *this;
}

kernel::Result<std::optional<std::string>> InputStream::read_line(kernel::Duration timeout, std::size_t max_length) {
  std::byte b{};
  for (;;) {
    if (!peek_byte(b, timeout)) {
      if (!is_open()) return kernel::Error{"stream '" + name() + "' closed"};
      return std::optional<std::string>{};  // the part read so far waits for the next call
    }
    ++pos_;
    const char c = static_cast<char>(b);
    if (c == '\n') break;
    // An overlong line is cut, not grown without bound; the rest up to '\n' is dropped.
    if (partial_line_.size() < max_length) partial_line_.push_back(c);
  }
  std::string line = std::move(partial_line_);
  partial_line_.clear();
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return std::optional<std::string>(std::move(line));
}

OutputStream& OutputStream::operator<<(std::string_view s) {
  if (!fail_ && !write_all(as_bytes(s))) fail_ = true;
  return *this;
}

OutputStream& OutputStream::operator<<(std::span<const std::byte> bytes) {
  if (!fail_ && !write_all(bytes)) fail_ = true;
  return *this;
}

OutputStream& OutputStream::operator<<(std::int64_t v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return *this << std::string_view(buf, static_cast<std::size_t>(r.ptr - buf));
}

OutputStream& OutputStream::operator<<(std::uint64_t v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return *this << std::string_view(buf, static_cast<std::size_t>(r.ptr - buf));
}

OutputStream& OutputStream::operator<<(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return *this << std::string_view(buf, static_cast<std::size_t>(r.ptr - buf));
}

OutputStream& OutputStream::operator<<(float v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return *this << std::string_view(buf, static_cast<std::size_t>(r.ptr - buf));
}

}  // namespace symb::io
