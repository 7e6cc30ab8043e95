// Table: how the shell's list commands print by default. The header row comes first, columns are
// aligned with at least two spaces between them, and every cell except those of the last column
// is one word (an empty cell shows as "-", a cell with white space or quotes is quoted the way the
// shell's own tokenizer reads it), so a script can split each row at white space and take the last
// column as the rest of the line. The same rows always print the same text.
#pragma once

#include <string>
#include <vector>

namespace symb::shell {

class Table {
 public:
  explicit Table(std::vector<std::string> header);

  // A row of exactly as many cells as the header has; cells are made safe as described above.
  void add(std::vector<std::string> row);
  std::size_t rows() const { return rows_.size(); }
  // The header and the rows, each line ending in '\n'.
  std::string str() const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace symb::shell
