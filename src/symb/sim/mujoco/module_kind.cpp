#include "symb/sim/mujoco/module_kind.hpp"

#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

namespace symb::sim::mujoco {

namespace {

// The gap between the body's underside and the floor on a wheeled module; the casters fill it.
constexpr double kWheeledClearance = 0.008;
// How far above a connector's centre its face's IR sensor sits.
constexpr double kIrAboveConnector = 0.02;

// A connector and an IR sensor at the centre of each face; the side faces' on the front half,
// whose hinge-free body keeps them level.
void place_faces(ModuleKind& kind, double ir_range) {
  const Vec3 s = kind.body.size;
  const std::array<Vec3, 4> centres = {Vec3{s[0] / 2, 0, 0}, Vec3{-s[0] / 2, 0, 0}, Vec3{s[0] / 4, s[1] / 2, 0},
                                       Vec3{s[0] / 4, -s[1] / 2, 0}};
  for (std::size_t i = 0; i < kFaces.size(); ++i) {
    kind.connectors.push_back({face_name(kFaces[i]), kFaces[i], centres[i]});
    Vec3 ir = centres[i];
    ir[2] += kIrAboveConnector;
    kind.ir.push_back({kFaces[i], ir, ir_range});
  }
}

}  // namespace

const char* face_name(Face face) {
  switch (face) {
    case Face::kFront: return "front";
    case Face::kBack: return "back";
    case Face::kLeft: return "left";
    case Face::kRight: return "right";
  }
  return "?";
}

Vec3 face_normal(Face face) {
  switch (face) {
    case Face::kFront: return {1, 0, 0};
    case Face::kBack: return {-1, 0, 0};
    case Face::kLeft: return {0, 1, 0};
    case Face::kRight: return {0, -1, 0};
  }
  return {0, 0, 0};
}

ModuleKind standard_kind() {
  ModuleKind kind;
  kind.name = "cube";
  place_faces(kind, 0.15);
  return kind;
}

ModuleKind long_kind() {
  ModuleKind kind;
  kind.name = "long";
  kind.body.size = {0.16, 0.10, 0.08};
  kind.body.mass = 0.6;
  kind.has_wheels = false;
  kind.hinge.gain = 8.0;
  kind.hinge.damping = 0.12;
  place_faces(kind, 0.15);
  return kind;
}

ModuleKind camera_kind() {
  ModuleKind kind = standard_kind();
  kind.name = "camera";
  const double front = kind.body.size[0] / 2;
  kind.camera = CameraSpec{Face::kFront, {front, 0, 0.03}, 32, 24, std::numbers::pi / 3, 2.0};
  kind.laser = LaserSpec{Face::kFront, {front, 0, -0.02}, 15, std::numbers::pi, 1.0};
  return kind;
}

double rest_height(const ModuleKind& kind) {
  return kind.body.size[2] / 2 + (kind.has_wheels ? kWheeledClearance : 0.0);
}

std::string check(const ModuleKind& kind) {
  std::ostringstream why;
  const auto& s = kind.body.size;
  if (!(s[0] > 0 && s[1] > 0 && s[2] > 0)) why << "body size must be positive on every axis; ";
  if (!(kind.body.mass > 0)) why << "body mass must be positive; ";
  if (kind.has_wheels) {
    const auto& w = kind.wheels;
    if (!(w.radius > kWheeledClearance && w.radius < s[2] / 2 + kWheeledClearance))
      why << "wheel radius must lie between the clearance (" << kWheeledClearance << " m) and half the body height; ";
    if (!(w.width > 0 && w.width < s[1] / 2)) why << "wheel width must be positive and under half the body width; ";
    if (!(w.mass > 0 && w.max_speed > 0 && w.gain > 0)) why << "wheel mass, max speed and gain must be positive; ";
  }
  const auto& h = kind.hinge;
  const double axis_norm = std::sqrt(h.axis[0] * h.axis[0] + h.axis[1] * h.axis[1] + h.axis[2] * h.axis[2]);
  if (!(axis_norm > 1e-9)) why << "hinge axis must not be zero; ";
  if (!(h.range[0] < h.range[1])) why << "hinge range must be [low, high] with low < high; ";
  if (!(h.gain > 0 && h.damping >= 0)) why << "hinge gain must be positive and damping not negative; ";
  std::set<std::string> names;
  for (const auto& c : kind.connectors) {
    if (c.name.empty()) why << "a connector has no name; ";
    if (!names.insert(c.name).second) why << "connector name '" << c.name << "' is used twice; ";
  }
  std::set<Face> ir_faces;
  for (const auto& ir : kind.ir) {
    if (!ir_faces.insert(ir.face).second) why << "two IR sensors on face " << face_name(ir.face) << "; ";
    if (!(ir.range > 0)) why << "IR range must be positive; ";
  }
  // A point on its face (the files check the same to a micrometre; this only catches code).
  auto on_face = [&](Face f, const Vec3& p) {
    const Vec3 n = face_normal(f);
    for (std::size_t i = 0; i < 3; ++i)
      if (n[i] != 0 ? std::abs(p[i] - n[i] * s[i] / 2) > 1e-6 : std::abs(p[i]) > s[i] / 2 + 1e-6) return false;
    return true;
  };
  if (kind.laser) {
    const LaserSpec& l = *kind.laser;
    if (!on_face(l.face, l.position)) why << "the laser is not on its face; ";
    if (!(l.rays >= 1 && l.rays <= kMaxLaserRays)) why << "a laser has 1 to " << kMaxLaserRays << " rays; ";
    if (!(l.field_of_view > 0 && l.field_of_view <= 2 * std::numbers::pi))
      why << "the laser's field of view must be in (0, 2 pi]; ";
    if (!(l.range > 0)) why << "the laser's range must be positive; ";
  }
  if (kind.camera) {
    const CameraSpec& c = *kind.camera;
    if (!on_face(c.face, c.position)) why << "the camera is not on its face; ";
    if (!(c.width >= 1 && c.width <= kMaxCameraWidth && c.height >= 1 && c.height <= kMaxCameraHeight))
      why << "a camera image is 1.." << kMaxCameraWidth << " x 1.." << kMaxCameraHeight << " pixels; ";
    if (!(c.field_of_view > 0 && c.field_of_view <= kMaxCameraFieldOfView))
      why << "the camera's field of view must be in (0, 170 degrees]; ";
    if (!(c.range > 0)) why << "the camera's range must be positive; ";
  }
  std::string text = why.str();
  if (text.size() >= 2) text.resize(text.size() - 2);
  return text;
}

}  // namespace symb::sim::mujoco
