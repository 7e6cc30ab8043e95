// Module kind files -> ModuleKind: a walk over the YAML tree on the sim layer's YAML scaffold
// (yaml_document.hpp), which bounds the text, locates every failure and keeps every exception
// inside this file. Ranges are wide enough for any module a person would build (millimetres to
// metres, grams to tens of kilograms) and narrow enough that MuJoCo never sees an absurd number.
#include "symb/sim/mujoco/module_kind_file.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "symb/kernel/source_text.hpp"
#include "symb/sim/yaml_document.hpp"

namespace symb::sim::mujoco {
namespace {

using yaml::Map;
using yaml::shown;
using yaml::Source;

constexpr double kMinLength = 0.001;  // m
constexpr double kMaxLength = 2.0;    // m
constexpr double kMinMass = 0.001;    // kg
constexpr double kMaxMass = 100.0;    // kg
// How far off its face a connector or IR sensor may be written (rounding in a hand-written file).
constexpr double kOnFaceTolerance = 1e-6;  // m
constexpr std::array<std::string_view, 4> kFaceNames = {"front", "back", "left", "right"};

class KindFileWalk {
 public:
  explicit KindFileWalk(const Source& src) : src_(src), rd_(src) {}

  ModuleKind top(const YAML::Node& root) {
    if (!root.IsDefined() || root.IsNull())
      src_.fail(SourceLocation{src_.file(), 1, 1},
                "the module kind is empty: it needs name, body, wheels, hinge, connectors, ir, laser and camera");
    Map m(src_, root, "the module kind", {"name", "body", "wheels", "hinge", "connectors", "ir", "laser", "camera"});
    ModuleKind k;
    k.name = name(m.require("name"), "name");
    body(m.require("body"), k.body);
    wheels(m.require("wheels"), k);
    hinge(m.require("hinge"), k.hinge);
    connectors(m.require("connectors"), k);
    ir(m.require("ir"), k);
    laser(m.require("laser"), k);
    camera(m.require("camera"), k);
    // The rules above are this file's; check() is the kind's own, which a world trusts.
    if (const std::string why = check(k); !why.empty()) src_.fail(root, "the module kind is not usable: " + why);
    return k;
  }

 private:
  std::string name(const YAML::Node& n, std::string_view what) const {
    std::string s = rd_.text(n, what);
    if (!kernel::is_identifier(s, 63))
      src_.fail(n, std::string(what) + " '" + shown(s) +
                       "' is not a valid name: 1 to 63 letters, digits or '_', starting with a letter or '_'");
    return s;
  }

  Vec3 vec3(const YAML::Node& n, std::string_view what, double lo, double hi) const {
    const auto v = rd_.list(n, what, 3);
    if (!n.IsSequence() || v.size() != 3) src_.fail(n, std::string(what) + " is [x, y, z]" + Map::got(n));
    Vec3 out{};
    static constexpr std::array<const char*, 3> kAxes = {" x", " y", " z"};
    for (std::size_t i = 0; i < 3; ++i) out[i] = rd_.number(v[i], std::string(what) + kAxes[i], lo, hi);
    return out;
  }

  void body(const YAML::Node& n, BodySpec& b) {
    Map m(src_, n, "body", {"size", "mass"});
    b.size = vec3(m.require("size"), "body size (m)", 0.01, kMaxLength);
    b.mass = rd_.number(m.require("mass"), "body mass (kg)", kMinMass, kMaxMass);
  }

  // A mapping, or the word `none` for a module without wheels.
  void wheels(const YAML::Node& n, ModuleKind& k) {
    if (n.IsScalar() && n.Scalar() == "none") {
      k.has_wheels = false;
      return;
    }
    if (!n.IsMap()) src_.fail(n, "wheels is a mapping (radius, width, mass, max_speed, gain) or none" + Map::got(n));
    Map m(src_, n, "wheels", {"radius", "width", "mass", "max_speed", "gain"});
    WheelSpec& w = k.wheels;
    const YAML::Node radius = m.require("radius"), width = m.require("width");
    w.radius = rd_.number(radius, "wheel radius (m)", kMinLength, kMaxLength);
    w.width = rd_.number(width, "wheel width (m)", kMinLength, kMaxLength);
    w.mass = rd_.number(m.require("mass"), "wheel mass (kg)", kMinMass, kMaxMass);
    w.max_speed = rd_.number(m.require("max_speed"), "wheel max_speed (m/s)", 0.001, 10);
    w.gain = rd_.number(m.require("gain"), "wheel gain (N*m per rad/s)", 1e-6, 100);
    k.has_wheels = true;
    // The gap under a wheeled body, which the wheels must reach across.
    const double clearance_wheeled = rest_height(k) - k.body.size[2] / 2;
    if (!(w.radius > clearance_wheeled && w.radius < k.body.size[2] / 2 + clearance_wheeled))
      src_.fail(radius, "wheel radius must lie between the clearance under the body (" +
                            yaml::Reader::fmt(clearance_wheeled) + " m) and half the body height plus it (" +
                            yaml::Reader::fmt(k.body.size[2] / 2 + clearance_wheeled) + " m), got " +
                            yaml::Reader::fmt(w.radius));
    if (!(w.width < k.body.size[1] / 2))
      src_.fail(width, "wheel width must be under half the body width (" + yaml::Reader::fmt(k.body.size[1] / 2) +
                           " m), got " + yaml::Reader::fmt(w.width));
  }

  void hinge(const YAML::Node& n, HingeSpec& h) {
    Map m(src_, n, "hinge", {"axis", "range", "gain", "damping"});
    const YAML::Node axis = m.require("axis");
    h.axis = vec3(axis, "hinge axis", -1, 1);
    if (!(std::hypot(h.axis[0], h.axis[1], h.axis[2]) > 1e-6)) src_.fail(axis, "hinge axis must not be zero");
    const YAML::Node range = m.require("range");
    const auto r = rd_.list(range, "hinge range", 2);
    if (!range.IsSequence() || r.size() != 2) src_.fail(range, "hinge range is [low, high] in rad" + Map::got(range));
    h.range[0] = rd_.number(r[0], "hinge range low (rad)", -std::numbers::pi, std::numbers::pi);
    h.range[1] = rd_.number(r[1], "hinge range high (rad)", -std::numbers::pi, std::numbers::pi);
    if (!(h.range[0] < h.range[1])) src_.fail(range, "hinge range must be [low, high] with low < high");
    h.gain = rd_.number(m.require("gain"), "hinge gain (N*m per rad)", 1e-3, 1000);
    h.damping = rd_.number(m.require("damping"), "hinge damping (N*m per rad/s)", 0, 100);
  }

  Face face(const YAML::Node& n) const {
    const std::string s = rd_.text(n, "face");
    for (std::size_t i = 0; i < kFaces.size(); ++i)
      if (s == kFaceNames[i]) return kFaces[i];
    std::string msg = "face must be front, back, left or right, got '" + shown(s) + "'";
    if (auto hint = os::closest_name(s, kFaceNames); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
    src_.fail(n, msg);
  }

  // A point on `f`: its coordinate along the face's normal is half the body's extent there, the
  // other two lie within the face.
  Vec3 on_face(const YAML::Node& n, std::string_view what, Face f, const BodySpec& b) const {
    const Vec3 p = vec3(n, what, -kMaxLength, kMaxLength);
    const Vec3 normal = face_normal(f);
    for (std::size_t i = 0; i < 3; ++i) {
      const double half = b.size[i] / 2;
      if (normal[i] != 0) {
        if (std::abs(p[i] - normal[i] * half) > kOnFaceTolerance)
          src_.fail(n, std::string(what) + " is not on the " + face_name(f) + " face: its " + "xyz"[i] + " must be " +
                           yaml::Reader::fmt(normal[i] * half) + " (half the body size), got " +
                           yaml::Reader::fmt(p[i]));
      } else if (std::abs(p[i]) > half + kOnFaceTolerance) {
        src_.fail(n, std::string(what) + " lies off the " + face_name(f) + " face: its " + "xyz"[i] +
                         " must be within +-" + yaml::Reader::fmt(half) + " m, got " + yaml::Reader::fmt(p[i]));
      }
    }
    return p;
  }

  void connectors(const YAML::Node& n, ModuleKind& k) {
    std::vector<YAML::Node> names;
    for (const YAML::Node& item : rd_.list(n, "connectors", kMaxConnectors)) {
      Map m(src_, item, "a connector", {"name", "face", "position"});
      ConnectorSpec c;
      const YAML::Node name_node = m.require("name");
      c.name = name(name_node, "connector name");
      for (std::size_t i = 0; i < k.connectors.size(); ++i)
        if (k.connectors[i].name == c.name)
          src_.fail(name_node, "connector name '" + c.name + "' is used twice (first at line " +
                                   std::to_string(src_.at(names[i]).line) + ")");
      c.face = face(m.require("face"));
      c.position = on_face(m.require("position"), "connector position (m)", c.face, k.body);
      k.connectors.push_back(std::move(c));
      names.push_back(name_node);
    }
  }

  void ir(const YAML::Node& n, ModuleKind& k) {
    std::vector<YAML::Node> faces;
    for (const YAML::Node& item : rd_.list(n, "ir", kFaces.size())) {
      Map m(src_, item, "an IR sensor", {"face", "position", "range"});
      IrSpec s;
      const YAML::Node fn = m.require("face");
      s.face = face(fn);
      for (std::size_t i = 0; i < k.ir.size(); ++i)
        if (k.ir[i].face == s.face)
          src_.fail(fn, std::string("two IR sensors on the ") + face_name(s.face) + " face (the first at line " +
                            std::to_string(src_.at(faces[i]).line) + ")");
      s.position = on_face(m.require("position"), "IR position (m)", s.face, k.body);
      s.range = rd_.number(m.require("range"), "IR range (m)", kMinLength, 5);
      k.ir.push_back(s);
      faces.push_back(fn);
    }
  }

  // The word `none`: the kind has no such sensor.
  static bool none(const YAML::Node& n) { return n.IsScalar() && n.Scalar() == "none"; }

  void laser(const YAML::Node& n, ModuleKind& k) {
    if (none(n)) return;
    if (!n.IsMap())
      src_.fail(n, "laser is a mapping (face, position, rays, field_of_view, range) or none" + Map::got(n));
    Map m(src_, n, "laser", {"face", "position", "rays", "field_of_view", "range"});
    LaserSpec l;
    l.face = face(m.require("face"));
    l.position = on_face(m.require("position"), "laser position (m)", l.face, k.body);
    l.rays = static_cast<std::size_t>(
        rd_.integer(m.require("rays"), "laser rays", 1, static_cast<std::int64_t>(kMaxLaserRays)));
    l.field_of_view = rd_.number(m.require("field_of_view"), "laser field_of_view (rad)", 1e-3, 2 * std::numbers::pi);
    l.range = rd_.number(m.require("range"), "laser range (m)", kMinLength, 10);
    k.laser = l;
  }

  void camera(const YAML::Node& n, ModuleKind& k) {
    if (none(n)) return;
    if (!n.IsMap())
      src_.fail(n, "camera is a mapping (face, position, width, height, field_of_view, range) or none" + Map::got(n));
    Map m(src_, n, "camera", {"face", "position", "width", "height", "field_of_view", "range"});
    CameraSpec c;
    c.face = face(m.require("face"));
    c.position = on_face(m.require("position"), "camera position (m)", c.face, k.body);
    c.width = static_cast<std::size_t>(
        rd_.integer(m.require("width"), "camera width (pixels)", 1, static_cast<std::int64_t>(kMaxCameraWidth)));
    c.height = static_cast<std::size_t>(
        rd_.integer(m.require("height"), "camera height (pixels)", 1, static_cast<std::int64_t>(kMaxCameraHeight)));
    c.field_of_view = rd_.number(m.require("field_of_view"), "camera field_of_view (rad)", 1e-3, kMaxCameraFieldOfView);
    c.range = rd_.number(m.require("range"), "camera range (m)", kMinLength, 10);
    k.camera = c;
  }

  const Source& src_;
  yaml::Reader rd_;
};

}  // namespace

kernel::Result<ModuleKind> parse_module_kind(std::string_view yaml_text, std::string_view file_name) {
  return yaml::parse_document<ModuleKind>(yaml_text, file_name, "a module kind", kMaxModuleKindBytes,
                                          kMaxModuleKindNesting, [](const Source& src, const YAML::Node& root) {
                                            KindFileWalk walk(src);
                                            return walk.top(root);
                                          });
}

kernel::Result<ModuleKind> load_module_kind(const std::string& path) {
  auto text = yaml::read_text_file(path, kMaxModuleKindBytes, "module kind");
  if (!text) return kernel::Error{text.error()};
  return parse_module_kind(*text, path);
}

}  // namespace symb::sim::mujoco
