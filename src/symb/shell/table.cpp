#include "symb/shell/table.hpp"

#include <algorithm>

#include "symb/shell/command_line.hpp"

namespace symb::shell {

Table::Table(std::vector<std::string> header) : header_(std::move(header)) {}

void Table::add(std::vector<std::string> row) {
  row.resize(header_.size());
  for (std::size_t c = 0; c < row.size(); ++c) {
    std::string& cell = row[c];
    if (c + 1 == row.size()) {
      // The last column is free text to the end of the line, kept on one line.
      for (char& ch : cell)
        if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f) ch = ' ';
      while (!cell.empty() && cell.back() == ' ') cell.pop_back();
      if (cell.empty()) cell = "-";
    } else {
      cell = cell.empty() ? std::string("-") : quote_word(cell);
    }
  }
  rows_.push_back(std::move(row));
}

std::string Table::str() const {
  std::vector<std::size_t> width(header_.size(), 0);
  const auto measure = [&](const std::vector<std::string>& row) {
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  };
  measure(header_);
  for (const auto& r : rows_) measure(r);
  std::string out;
  const auto emit = [&](const std::vector<std::string>& row) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      out += row[c];
      if (c + 1 < row.size()) out.append(width[c] - row[c].size() + 2, ' ');
    }
    out += '\n';
  };
  emit(header_);
  for (const auto& r : rows_) emit(r);
  return out;
}

}  // namespace symb::shell
