// Fuzzes module kind files: bytes -> YAML -> ModuleKind. Any input must give a kind or an error
// "fuzz.yaml:LINE:COLUMN: message" with LINE a line the input has, never a crash or a hang. Every
// accepted kind must be one the world can trust: check() finds nothing wrong with it, its
// numbers are finite, its lists within their bounds, its connectors, IR sensors, laser and camera
// on the body.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "symb/sim/mujoco/module_kind_file.hpp"

#include "located_error.hpp"

using namespace symb;
using namespace symb::sim::mujoco;

namespace {

bool located_in(const std::string& e, std::string_view text) {
  const std::string prefix = "fuzz.yaml:";
  if (e.rfind(prefix, 0) != 0) return false;
  const auto loc = kernel::split_location(std::string_view(e).substr(prefix.size()));
  if (!loc.at || loc.message.empty()) return false;
  std::size_t lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  if (!text.empty() && text.back() != '\n') ++lines;
  return loc.at->line >= 1 && loc.at->line <= std::max<std::size_t>(lines, 1) && loc.at->column >= 1;
}

bool finite(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

bool on_body(const Vec3& p, const BodySpec& b) {
  for (std::size_t i = 0; i < 3; ++i)
    if (std::abs(p[i]) > b.size[i] / 2 + 1e-5) return false;
  return true;
}

void check_sound(const ModuleKind& k) {
  if (!check(k).empty()) std::abort();
  if (!finite(k.body.size) || !std::isfinite(k.body.mass) || !finite(k.hinge.axis)) std::abort();
  if (k.connectors.size() > kMaxConnectors || k.ir.size() > kFaces.size()) std::abort();
  for (const auto& c : k.connectors)
    if (!finite(c.position) || !on_body(c.position, k.body)) std::abort();
  for (const auto& s : k.ir)
    if (!finite(s.position) || !on_body(s.position, k.body) || !std::isfinite(s.range)) std::abort();
  if (k.laser &&
      (!finite(k.laser->position) || !on_body(k.laser->position, k.body) || k.laser->rays < 1 ||
       k.laser->rays > kMaxLaserRays || !std::isfinite(k.laser->field_of_view) || !std::isfinite(k.laser->range)))
    std::abort();
  if (k.camera && (!finite(k.camera->position) || !on_body(k.camera->position, k.body) || k.camera->width < 1 ||
                   k.camera->width > kMaxCameraWidth || k.camera->height < 1 || k.camera->height > kMaxCameraHeight ||
                   !std::isfinite(k.camera->field_of_view) || !std::isfinite(k.camera->range)))
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto k = parse_module_kind(text, "fuzz.yaml");
  if (!k) {
    if (!located_in(k.error(), text)) std::abort();
    return 0;
  }
  check_sound(*k);
  return 0;
}
