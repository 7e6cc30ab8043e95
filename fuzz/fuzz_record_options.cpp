// Fuzzes `symb run`'s recording options as typed on the command line: the format word and the
// `--record-robots` list (names and FIRST..LAST ranges). Any input must give a value or an error
// that names its column within the text, never a crash; a list it accepts picks valid robots,
// each once, in the world's order.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "symb/apps/run/record_options.hpp"

using namespace symb::apps::run;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (int i = 0; i < 40; ++i) n.push_back("t" + std::to_string(i));
    n.push_back("leader");
    return n;
  }();
  (void)parse_record_format(text);
  auto picked = resolve_record_robots(text, names);
  if (picked) {
    for (std::size_t k = 0; k < picked->size(); ++k) {
      if ((*picked)[k] >= names.size()) std::abort();
      if (k > 0 && (*picked)[k] <= (*picked)[k - 1]) std::abort();
    }
  } else {
    const std::string& e = picked.error();
    const std::string prefix = "--record-robots: column ";
    if (e.compare(0, prefix.size(), prefix) != 0) std::abort();
    const unsigned long column = std::strtoul(e.c_str() + prefix.size(), nullptr, 10);
    if (column < 1 || column > size + 1) std::abort();
  }
  return 0;
}
