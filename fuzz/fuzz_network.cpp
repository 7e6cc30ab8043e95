// Fuzzes the network description format and weight lists: any text must give a description or an
// error "LINE:COLUMN: message", never a crash or a hang; every accepted description must build
// its network, take its genome and step to finite outputs. The same bytes are also read as a
// weight list.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "symb/control/network/description.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::control::network;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto d = parse_description(text);
  if (!d) {
    if (!located(d.error())) std::abort();
  } else {
    auto n = Network::create(d->topology);
    if (!n) std::abort();
    Network& net = n.value();
    if (d->weights && !net.set_genome(*d->weights)) std::abort();
    if (!d->tau.empty() && !net.set_time_constants(d->tau)) std::abort();
    std::vector<float> x(net.input_count());
    for (int t = 0; t < 50; ++t) {
      for (std::size_t k = 0; k < x.size(); ++k) x[k] = static_cast<float>((t * (k + 3)) % 7) - 3.0f;
      for (float o : net.step(x))
        if (!std::isfinite(o)) std::abort();
    }
  }
  auto w = parse_numbers(text);
  if (!w) {
    if (!located(w.error())) std::abort();
  } else {
    for (float v : *w)
      if (!std::isfinite(v)) std::abort();
  }
  return 0;
}
