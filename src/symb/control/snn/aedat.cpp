#include "symb/control/snn/aedat.hpp"

#include <cstdint>
#include <string>

namespace symb::control::snn {

namespace {

constexpr std::string_view kVersionLine = "#!AER-DAT2.0";
constexpr std::size_t kRecordBytes = 8;

void put32(std::string& out, std::uint32_t v) {
  out.push_back(static_cast<char>(v >> 24));
  out.push_back(static_cast<char>(v >> 16));
  out.push_back(static_cast<char>(v >> 8));
  out.push_back(static_cast<char>(v));
}

std::uint32_t get32(const char* p) {
  const auto b = [p](int i) { return static_cast<std::uint32_t>(static_cast<unsigned char>(p[i])); };
  return (b(0) << 24) | (b(1) << 16) | (b(2) << 8) | b(3);
}

kernel::Error at(std::size_t line, std::size_t column, const std::string& message) {
  return kernel::Error{std::to_string(line) + ":" + std::to_string(column) + ": " + message};
}

// A header line [begin, end of its text) and where the next line starts, or an error when the
// line has no "\r\n" end.
struct Line {
  std::size_t text_end = 0;
  std::size_t next = 0;
};

kernel::Result<Line> header_line(std::string_view bytes, std::size_t begin, std::size_t line_no) {
  const std::size_t nl = bytes.find('\n', begin);
  if (nl == std::string_view::npos)
    return at(line_no, bytes.size() - begin + 1, "header line without its \\r\\n end (the file ends)");
  if (nl == begin || bytes[nl - 1] != '\r')
    return at(line_no, nl - begin + 1, "header line ends in \\n without the \\r before it");
  // The writer cuts a comment at its first '\r' (aedat_header), so a stray one inside a line is
  // no comment it could have written: refused, which keeps read -> write -> read exact.
  if (const std::size_t cr = bytes.substr(begin, nl - 1 - begin).find('\r'); cr != std::string_view::npos)
    return at(line_no, cr + 1, "header line holds a \r before its \r\n end");
  return Line{nl - 1, nl + 1};
}

}  // namespace

std::string aedat_header(std::span<const std::string> comments) {
  std::string out(kVersionLine);
  out += "\r\n";
  for (const std::string& c : comments) {
    out += "# ";
    out.append(c, 0, c.find_first_of("\r\n"));
    out += "\r\n";
  }
  return out;
}

void append_aedat_records(std::string& out, std::span<const AerEvent> events) {
  out.reserve(out.size() + kRecordBytes * events.size());
  for (const AerEvent& e : events) {
    put32(out, e.address);
    put32(out, e.timestamp_us);
  }
}

kernel::Result<AedatFile> read_aedat(std::string_view bytes) {
  if (bytes.empty() || bytes[0] != '#') return at(1, 1, "not an AEDAT file: no version line \"#!AER-DAT2.0\"");
  auto first = header_line(bytes, 0, 1);
  if (!first) return kernel::Error{first.error()};
  const std::string_view version = bytes.substr(0, first->text_end);
  if (version != kVersionLine) {
    std::size_t col = 0;
    while (col < version.size() && col < kVersionLine.size() && version[col] == kVersionLine[col]) ++col;
    const bool versioned = version.substr(0, 9) == "#!AER-DAT";
    return at(1, col + 1,
              versioned
                  ? "AEDAT version \"" + std::string(version.substr(9)) + "\" is not 2.0 (only AER-DAT2.0 is read)"
                  : std::string("the first line is not the version line \"#!AER-DAT2.0\""));
  }
  AedatFile file;
  std::size_t pos = first->next;
  std::size_t line_no = 2;
  while (pos < bytes.size() && bytes[pos] == '#') {
    auto l = header_line(bytes, pos, line_no);
    if (!l) return kernel::Error{l.error()};
    std::size_t text = pos + 1;
    if (text < l->text_end && bytes[text] == ' ') ++text;  // the writer's "# "
    file.header.emplace_back(bytes.substr(text, l->text_end - text));
    pos = l->next;
    ++line_no;
  }
  const std::size_t body = bytes.size() - pos;
  const std::size_t records = body / kRecordBytes;
  if (body % kRecordBytes != 0)
    return kernel::Error{"byte " + std::to_string(pos + records * kRecordBytes) + ": trailing partial record of " +
                         std::to_string(body % kRecordBytes) + " bytes (a record is 8)"};
  file.events.resize(records);
  const char* p = bytes.data() + pos;
  for (AerEvent& e : file.events) {
    e.address = get32(p);
    e.timestamp_us = get32(p + 4);
    p += kRecordBytes;
  }
  return file;
}

}  // namespace symb::control::snn
