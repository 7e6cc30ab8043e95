#include "symb/apps/text_file.hpp"

#include <fstream>
#include <sstream>

namespace symb::apps {

kernel::Result<std::string> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return kernel::Error{"cannot read " + path.string()};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

kernel::Status write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) return kernel::Error{"cannot write " + path.string()};
  return {};
}

}  // namespace symb::apps
