#include "symb/sim/mujoco/mjcf_model.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>

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

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

// Numbers are written with 17 significant digits so the model holds exactly the doubles given.
struct Xml {
  std::ostringstream out;
  Xml() { out.precision(17); }
  Xml& v3(double x, double y, double z) {
    out << x << ' ' << y << ' ' << z;
    return *this;
  }
};

void write_module(Xml& xml, const ModuleSpec& module) {
  const ModuleKind& k = module.kind;
  const std::string& n = module.name;
  const double lx = k.body.size[0], ly = k.body.size[1], lz = k.body.size[2];
  const double half_mass = k.body.mass / 2;
  const double h = rest_height(k);
  const double clearance = h - lz / 2;
  auto& o = xml.out;

  o << "    <body name=\"" << n << ".base\" pos=\"";
  xml.v3(module.start.x, module.start.y, h);
  o << "\" quat=\"" << std::cos(module.start.yaw / 2) << " 0 0 " << std::sin(module.start.yaw / 2) << "\">\n";
  o << "      <freejoint name=\"" << n << ".free\"/>\n";
  o << "      <geom name=\"" << n << ".base\" type=\"box\" size=\"";
  xml.v3(lx / 4, ly / 2, lz / 2);
  o << "\" pos=\"" << lx / 4 << " 0 0\" mass=\"" << half_mass << "\" friction=\"" << kBodyFriction << "\"/>\n";
  if (k.has_wheels) {
    o << "      <geom name=\"" << n << ".caster_f\" type=\"sphere\" size=\"" << clearance << "\" pos=\"";
    xml.v3(lx / 2 - clearance - 0.004, 0, -lz / 2);
    o << "\" mass=\"" << kCasterMass << "\" friction=\"" << kCasterFriction << "\"/>\n";
    const double wy = ly / 2 - k.wheels.width / 2;
    const double wz = -lz / 2 - clearance + k.wheels.radius;
    for (const auto& [side, y] : std::array<std::pair<const char*, double>, 2>{{{"l", wy}, {"r", -wy}}}) {
      o << "      <body name=\"" << n << ".wheel_" << side << "\" pos=\"";
      xml.v3(0, y, wz);
      o << "\">\n";
      o << "        <joint name=\"" << n << ".wheel_" << side << "\" type=\"hinge\" axis=\"0 1 0\" armature=\""
        << kArmature << "\"/>\n";
      o << "        <geom name=\"" << n << ".wheel_" << side << "\" type=\"cylinder\" size=\"" << k.wheels.radius << ' '
        << k.wheels.width / 2 << "\" zaxis=\"0 1 0\" mass=\"" << k.wheels.mass << "\" friction=\"" << kWheelFriction
        << "\"/>\n";
      o << "      </body>\n";
    }
  }
  o << "      <body name=\"" << n << ".tail\">\n";
  o << "        <joint name=\"" << n << ".hinge\" type=\"hinge\" axis=\"";
  xml.v3(k.hinge.axis[0], k.hinge.axis[1], k.hinge.axis[2]);
  o << "\" limited=\"true\" range=\"" << k.hinge.range[0] << ' ' << k.hinge.range[1] << "\" damping=\""
    << k.hinge.damping << "\" armature=\"" << kArmature << "\"/>\n";
  o << "        <geom name=\"" << n << ".tail\" type=\"box\" size=\"";
  xml.v3(lx / 4, ly / 2, lz / 2);
  o << "\" pos=\"" << -lx / 4 << " 0 0\" mass=\"" << half_mass << "\" friction=\"" << kBodyFriction << "\"/>\n";
  if (k.has_wheels) {
    o << "        <geom name=\"" << n << ".caster_b\" type=\"sphere\" size=\"" << clearance << "\" pos=\"";
    xml.v3(-(lx / 2 - clearance - 0.004), 0, -lz / 2);
    o << "\" mass=\"" << kCasterMass << "\" friction=\"" << kCasterFriction << "\"/>\n";
  }
  o << "      </body>\n";
  o << "    </body>\n";
}

}  // namespace

kernel::Result<std::string> mjcf_text(const std::vector<ModuleSpec>& modules, const ModelOptions& options) {
  if (modules.empty()) return kernel::Error{"a model needs at least one module"};
  if (options.spare_welds == 0) return kernel::Error{"a model needs at least one spare weld to dock"};
  if (!(options.weld_time_constant >= 2 * kTimestep))
    return kernel::Error{"weld time constant must be at least two time steps (" + std::to_string(2 * kTimestep) +
                         " s)"};
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
  // The dense solver's matrices are rows x rows and rows x dofs; twice that, and slack.
  const std::size_t nstack = 2 * njmax * (njmax + nv) + 200000;

  Xml xml;
  auto& o = xml.out;
  o << "<mujoco model=\"symbricator organism\">\n";
  o << "  <compiler angle=\"radian\"/>\n";
  o << "  <option timestep=\"" << kTimestep << "\" integrator=\"Euler\"/>\n";
  o << "  <size njmax=\"" << njmax << "\" nconmax=\"" << nconmax << "\" nstack=\"" << nstack << "\"/>\n";
  o << "  <worldbody>\n";
  o << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" friction=\"" << kFloorFriction << "\"/>\n";
  for (const auto& m : modules) write_module(xml, m);
  o << "  </worldbody>\n";
  o << "  <contact>\n";
  for (const auto& m : modules) {
    if (!m.kind.has_wheels) continue;
    for (const char* side : {"l", "r"})
      o << "    <exclude body1=\"" << m.name << ".tail\" body2=\"" << m.name << ".wheel_" << side << "\"/>\n";
  }
  o << "  </contact>\n";
  o << "  <equality>\n";
  for (std::size_t k = 0; k < options.spare_welds; ++k)
    o << "    <weld name=\"spare_weld_" << k << "\" body1=\"" << modules.front().name
      << ".base\" active=\"false\" solref=\"" << options.weld_time_constant << " 1\"/>\n";
  o << "  </equality>\n";
  o << "  <actuator>\n";
  for (const auto& m : modules) {
    const auto& hinge = m.kind.hinge;
    o << "    <position name=\"" << m.name << ".hinge\" joint=\"" << m.name << ".hinge\" kp=\"" << hinge.gain
      << "\" ctrllimited=\"true\" ctrlrange=\"" << hinge.range[0] << ' ' << hinge.range[1] << "\"/>\n";
    if (!m.kind.has_wheels) continue;
    for (const char* side : {"l", "r"})
      o << "    <velocity name=\"" << m.name << ".wheel_" << side << "\" joint=\"" << m.name << ".wheel_" << side
        << "\" kv=\"" << m.kind.wheels.gain << "\"/>\n";
  }
  o << "  </actuator>\n";
  o << "</mujoco>\n";
  return o.str();
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
