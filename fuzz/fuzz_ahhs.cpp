// Fuzzes the AHHS description text: any input must give a network or an error
// "LINE:COLUMN: message", never a crash or a hang. Every accepted network must survive the round
// trip through to_text() unchanged, compile into a model and run a hundred steps with every level
// within its hormone's bounds and every actuator within [-1, 1], and a mutation must leave it valid.
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "symb/control/ahhs/model.hpp"
#include "symb/control/ahhs/mutation.hpp"
#include "symb/control/ahhs/parser.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb::control::ahhs;

namespace {

void run(const Network& n) {
  auto m = Model::create(n);
  if (!m) std::abort();
  if (n.compartments > 2000 || n.rules.size() > 2000) return;  // keep each input fast
  float sensors[kMaxSensorIndex];
  for (int t = 0; t < 100; ++t) {
    for (std::size_t k = 0; k < kMaxSensorIndex; ++k) sensors[k] = static_cast<float>((t * (k + 3)) % 101) / 100.0f;
    m.value().step(sensors);
    for (std::uint32_t c = 0; c < m->compartments(); ++c)
      for (std::size_t h = 0; h < m->hormones(); ++h) {
        const float x = m->levels(c)[h];
        if (!(x >= n.hormones[h].min && x <= n.hormones[h].max)) std::abort();
      }
    for (float a : m->actuators())
      if (!(a >= -1.0f && a <= 1.0f)) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto n = parse_network(text);
  if (!n) {
    if (!located(n.error())) std::abort();
    return 0;
  }
  auto back = parse_network(to_text(*n));
  if (!back || !(*back == *n)) std::abort();
  run(*n);
  Network mutated = *n;
  symb::kernel::RandomStream random(size);
  mutate(mutated, random);
  if (!validate(mutated)) std::abort();
  run(mutated);
  return 0;
}
