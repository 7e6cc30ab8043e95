#include "symb/sim/mujoco/mjcf_model.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <set>
#include <sstream>
#include <utility>

#include <mujoco/mujoco.h>

namespace symb::sim::mujoco {

static_assert(mjVERSION_HEADER == 222,
              "written against MuJoCo 2.2.2: from 3.0 the weld switch is mjData.eq_active, not mjModel.eq_active");

namespace {

// Friction (sliding, torsional, rolling). MuJoCo gives a contact the larger of its two geoms'
// values, so the floor is slippery and whatever should grip says so: wheels grip, casters slide.
constexpr const char* kFloorFriction = "0.05 0.005 0.0001";
constexpr const char* kBodyFriction = "0.5 0.005 0.0001";
constexpr const char* kWheelFriction = "1.2 0.005 0.0001";
constexpr const char* kCasterFriction = "0.05 0.005 0.0001";
// Rotor inertia added to the hinge and the wheels (kg*m^2): 2.2.2's Euler step treats actuator
// gains explicitly, and a wheel spinning in the air has too little inertia for its servo at 2 ms.
constexpr double kArmature = 0.0002;
constexpr double kCasterMass = 0.002;
// Constraint rows reserved per module (contacts: wheels, casters, sides touching a neighbour, four
// rows each in MuJoCo's pyramidal friction cone) and per weld (six), plus room for the rest.
constexpr std::size_t kRowsPerModule = 64;
constexpr std::size_t kRowsPerWeld = 6;
constexpr std::size_t kContactsPerModule = 16;
// The stack: MuJoCo 2.2.2's peak use (d->maxuse_stack) in a docked chain of standard modules that
// drives while its hinges wave (1500 steps; tests/sim/mujoco_sensors_test.cpp prints it) was 7,398
// numbers for 5 modules (45 dofs, dense solver), 168,138 for 20 (180 dofs) and 1,027,908 for 50
// (450 dofs); a crowd of 50 loose modules driving into each other for 5 s, 1,035,398 (6: 10,722).
// That is about 5.1 nv^2, the sparse solver's nv x nv matrices, plus vectors per constraint row;
// contacts barely matter. The reserve is kStackSafety times 6 nv^2 + 16 njmax, plus a floor for
// small models: 50 modules reserve 3.9 M numbers (31 MB) where the dense worst case (2 njmax
// (njmax + nv)) reserved 29 M (234 MB).
constexpr std::size_t kStackPerDof2 = 6;
constexpr std::size_t kStackPerRow = 16;
constexpr std::size_t kStackSafety = 3;
constexpr std::size_t kStackFloor = 50000;

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

// The shortest text that reads back as the same double: the model holds exactly the numbers given.
std::string num(double value) {
  std::array<char, 32> text{};
  const auto end = std::to_chars(text.data(), text.data() + text.size(), value).ptr;
  return {text.data(), end};
}

std::string nums(std::initializer_list<double> values) {
  std::string text;
  for (const double v : values) text += (text.empty() ? "" : " ") + num(v);
  return text;
}

using Attributes = std::vector<std::pair<const char*, std::string>>;

// Writes indented XML elements. Attribute values are names checked by valid_name() with fixed
// suffixes, and numbers: none needs escaping.
class XmlWriter {
 public:
  void open(const char* tag, const Attributes& attributes = {}) {
    start(tag, attributes);
    text_ += ">\n";
    open_.push_back(tag);
  }
  void leaf(const char* tag, const Attributes& attributes) {
    start(tag, attributes);
    text_ += "/>\n";
  }
  void close() {
    const char* tag = open_.back();
    open_.pop_back();
    text_.append(2 * open_.size(), ' ');
    text_ += std::string("</") + tag + ">\n";
  }
  const std::string& text() const { return text_; }

 private:
  void start(const char* tag, const Attributes& attributes) {
    text_.append(2 * open_.size(), ' ');
    text_ += std::string("<") + tag;
    for (const auto& [name, value] : attributes) text_ += std::string(" ") + name + "=\"" + value + "\"";
  }
  std::string text_;
  std::vector<const char*> open_;
};

void write_module(XmlWriter& xml, const ModuleSpec& module) {
  const ModuleKind& k = module.kind;
  const std::string& n = module.name;
  const double lx = k.body.size[0], ly = k.body.size[1], lz = k.body.size[2];
  const std::string half_mass = num(k.body.mass / 2);
  const double h = rest_height(k);
  const double clearance = h - lz / 2;
  const double caster_x = lx / 2 - clearance - 0.004;
  const double yaw = module.start.yaw;

  xml.open("body", {{"name", n + ".base"},
                    {"pos", nums({module.start.x, module.start.y, h})},
                    {"quat", nums({std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)})}});
  xml.leaf("freejoint", {{"name", n + ".free"}});
  xml.leaf("geom", {{"name", n + ".base"},
                    {"type", "box"},
                    {"size", nums({lx / 4, ly / 2, lz / 2})},
                    {"pos", nums({lx / 4, 0, 0})},
                    {"mass", half_mass},
                    {"friction", kBodyFriction}});
  if (k.has_wheels) {
    xml.leaf("geom", {{"name", n + ".caster_f"},
                      {"type", "sphere"},
                      {"size", num(clearance)},
                      {"pos", nums({caster_x, 0, -lz / 2})},
                      {"mass", num(kCasterMass)},
                      {"friction", kCasterFriction}});
    const double wy = ly / 2 - k.wheels.width / 2;
    const double wz = -lz / 2 - clearance + k.wheels.radius;
    for (const auto& [side, y] : std::array<std::pair<const char*, double>, 2>{{{"l", wy}, {"r", -wy}}}) {
      const std::string wheel = n + ".wheel_" + side;
      xml.open("body", {{"name", wheel}, {"pos", nums({0, y, wz})}});
      xml.leaf("joint", {{"name", wheel}, {"type", "hinge"}, {"axis", "0 1 0"}, {"armature", num(kArmature)}});
      xml.leaf("geom", {{"name", wheel},
                        {"type", "cylinder"},
                        {"size", nums({k.wheels.radius, k.wheels.width / 2})},
                        {"zaxis", "0 1 0"},
                        {"mass", num(k.wheels.mass)},
                        {"friction", kWheelFriction}});
      xml.close();
    }
  }
  xml.open("body", {{"name", n + ".tail"}});
  xml.leaf("joint", {{"name", n + ".hinge"},
                     {"type", "hinge"},
                     {"axis", nums({k.hinge.axis[0], k.hinge.axis[1], k.hinge.axis[2]})},
                     {"limited", "true"},
                     {"range", nums({k.hinge.range[0], k.hinge.range[1]})},
                     {"damping", num(k.hinge.damping)},
                     {"armature", num(kArmature)}});
  xml.leaf("geom", {{"name", n + ".tail"},
                    {"type", "box"},
                    {"size", nums({lx / 4, ly / 2, lz / 2})},
                    {"pos", nums({-lx / 4, 0, 0})},
                    {"mass", half_mass},
                    {"friction", kBodyFriction}});
  if (k.has_wheels) {
    xml.leaf("geom", {{"name", n + ".caster_b"},
                      {"type", "sphere"},
                      {"size", num(clearance)},
                      {"pos", nums({-caster_x, 0, -lz / 2})},
                      {"mass", num(kCasterMass)},
                      {"friction", kCasterFriction}});
  }
  xml.close();
  xml.close();
}

}  // namespace

kernel::Result<std::string> mjcf_text(const std::vector<ModuleSpec>& modules, const ModelOptions& options) {
  if (modules.empty()) return kernel::Error{"a model needs at least one module"};
  if (options.spare_welds == 0) return kernel::Error{"a model needs at least one spare weld to dock"};
  if (options.obstacles.size() > kMaxObstacles)
    return kernel::Error{"at most " + std::to_string(kMaxObstacles) + " obstacles, got " +
                         std::to_string(options.obstacles.size())};
  for (std::size_t k = 0; k < options.obstacles.size(); ++k) {
    const Obstacle& o = options.obstacles[k];
    const bool sized =
        o.size[0] > 0 && o.size[1] > 0 && o.size[2] > 0 && o.size[0] <= 100 && o.size[1] <= 100 && o.size[2] <= 100;
    if (!sized || !std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.yaw))
      return kernel::Error{"obstacle " + std::to_string(k) +
                           ": its position and yaw must be finite and its size in (0, 100] m on every axis"};
  }
  if (!(options.weld_time_constant >= 2 * kTimestep))
    return kernel::Error{"weld time constant must be at least two time steps (" + num(2 * kTimestep) + " s)"};
  std::set<std::string> names;
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const auto& m = modules[i];
    if (!valid_name(m.name))
      return kernel::Error{"module " + std::to_string(i) + ": name '" + m.name +
                           "' must be letters, digits and '_' only, and not empty"};
    if (!names.insert(m.name).second)
      return kernel::Error{"module " + std::to_string(i) + ": name '" + m.name + "' is used twice"};
    if (const std::string why = check(m.kind); !why.empty())
      return kernel::Error{"module '" + m.name + "' (kind '" + m.kind.name + "'): " + why};
  }

  std::size_t nv = 0;
  for (const auto& m : modules) nv += 6 + 1 + (m.kind.has_wheels ? 2 : 0);
  const std::size_t njmax = kRowsPerModule * modules.size() + kRowsPerWeld * options.spare_welds + 100;
  const std::size_t nconmax = kContactsPerModule * modules.size() + 50;
  const std::size_t nstack = stack_numbers(nv, njmax);

  XmlWriter xml;
  xml.open("mujoco", {{"model", "symbricator organism"}});
  xml.leaf("compiler", {{"angle", "radian"}});
  xml.leaf("option", {{"timestep", num(kTimestep)}, {"integrator", "Euler"}});
  xml.leaf(
      "size",
      {{"njmax", std::to_string(njmax)}, {"nconmax", std::to_string(nconmax)}, {"nstack", std::to_string(nstack)}});
  xml.open("worldbody");
  xml.leaf("geom", {{"name", "floor"}, {"type", "plane"}, {"size", "0 0 1"}, {"friction", kFloorFriction}});
  for (std::size_t k = 0; k < options.obstacles.size(); ++k) {
    const Obstacle& o = options.obstacles[k];
    xml.leaf("geom", {{"name", "obstacle_" + std::to_string(k)},
                      {"type", "box"},
                      {"size", nums({o.size[0] / 2, o.size[1] / 2, o.size[2] / 2})},
                      {"pos", nums({o.x, o.y, o.size[2] / 2})},
                      {"quat", nums({std::cos(o.yaw / 2), 0, 0, std::sin(o.yaw / 2)})},
                      {"friction", kBodyFriction}});
  }
  for (const auto& m : modules) write_module(xml, m);
  xml.close();
  xml.open("contact");
  for (const auto& m : modules) {
    if (!m.kind.has_wheels) continue;
    for (const char* side : {"l", "r"})
      xml.leaf("exclude", {{"body1", m.name + ".tail"}, {"body2", m.name + ".wheel_" + side}});
  }
  xml.close();
  xml.open("equality");
  for (std::size_t k = 0; k < options.spare_welds; ++k)
    xml.leaf("weld", {{"name", "spare_weld_" + std::to_string(k)},
                      {"body1", modules.front().name + ".base"},
                      {"active", "false"},
                      {"solref", nums({options.weld_time_constant, 1})}});
  xml.close();
  xml.open("actuator");
  for (const auto& m : modules) {
    const auto& hinge = m.kind.hinge;
    xml.leaf("position", {{"name", m.name + ".hinge"},
                          {"joint", m.name + ".hinge"},
                          {"kp", num(hinge.gain)},
                          {"ctrllimited", "true"},
                          {"ctrlrange", nums({hinge.range[0], hinge.range[1]})}});
    if (!m.kind.has_wheels) continue;
    for (const char* side : {"l", "r"}) {
      const std::string wheel = m.name + ".wheel_" + side;
      xml.leaf("velocity", {{"name", wheel}, {"joint", wheel}, {"kv", num(m.kind.wheels.gain)}});
    }
  }
  xml.close();
  xml.close();
  return xml.text();
}

std::size_t stack_numbers(std::size_t dofs, std::size_t rows) {
  return kStackSafety * (kStackPerDof2 * dofs * dofs + kStackPerRow * rows) + kStackFloor;
}

void ModelDeleter::operator()(mjModel_* model) const { mj_deleteModel(model); }

kernel::Result<ModelPtr> load_mjcf(const std::string& text) {
  // mjVFS holds 2000 file names of 1000 bytes: 2 MB, too big for the stack.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  constexpr const char* kFileName = "symbricator_organism.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kFileName, static_cast<int>(text.size())) != 0)
    return kernel::Error{"MuJoCo's virtual file system refused the model text"};
  const int file = mj_findFileVFS(vfs.get(), kFileName);
  std::memcpy(vfs->filedata[file], text.data(), text.size());
  std::array<char, 1000> error{};
  mjModel* model = mj_loadXML(kFileName, vfs.get(), error.data(), static_cast<int>(error.size()));
  mj_deleteVFS(vfs.get());
  if (model == nullptr) return kernel::Error{std::string("MuJoCo could not compile the model: ") + error.data()};
  return ModelPtr(model);
}

}  // namespace symb::sim::mujoco
