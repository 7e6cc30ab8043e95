// ModuleKind: what one kind of robot module is made of, as plain data (the paper's bodies,
// actuators, connectors and sensors). A kind is the model; the 3D world (mujoco_world.hpp) holds
// the running state. Two kinds differ only in their numbers: nothing about a kind lives in code.
//
// A module is a box of `body.size` split across its width into two halves joined by one hinge at
// its centre: the front half ("base", the module's root, free in the world) and the back half
// ("tail", which the hinge bends). With wheels, two wheels sit in wells at the centre of the sides
// (their outer faces flush with the body) and two small low-friction casters under the front and
// back ends keep the body level; without wheels the body rests on the floor.
//
// Frame: the module frame has x forward (the front face at +size.x / 2), y to the left, z up, and
// its origin at the body's centre. Lengths are metres, masses kilograms, angles radians.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace symb::sim::mujoco {

using Vec3 = std::array<double, 3>;

// The four side faces of a module's box.
enum class Face { kFront, kBack, kLeft, kRight };
inline constexpr std::array<Face, 4> kFaces = {Face::kFront, Face::kBack, Face::kLeft, Face::kRight};
const char* face_name(Face face);
// The face's outward normal in the module frame (unit, horizontal).
Vec3 face_normal(Face face);

struct BodySpec {
  Vec3 size = {0.10, 0.10, 0.08};  // full box extent along x, y, z
  double mass = 0.40;              // both halves together, wheels not included

  friend bool operator==(const BodySpec&, const BodySpec&) = default;
};

struct WheelSpec {
  double radius = 0.025;
  double width = 0.012;
  double mass = 0.02;       // each
  double max_speed = 0.15;  // rim speed, m/s; commands beyond it are clamped
  double gain = 0.004;      // velocity servo, N*m per rad/s of speed error

  friend bool operator==(const WheelSpec&, const WheelSpec&) = default;
};

struct HingeSpec {
  Vec3 axis = {0, 1, 0};                      // in the module frame, through the body's centre
  std::array<double, 2> range = {-1.2, 1.2};  // rad; the joint is limited to it
  double gain = 4.0;                          // position servo, N*m per rad of error
  double damping = 0.06;                      // N*m per rad/s, keeps the servo from ringing

  friend bool operator==(const HingeSpec&, const HingeSpec&) = default;
};

struct ConnectorSpec {
  std::string name;  // unique within the kind
  Face face = Face::kFront;
  Vec3 position{};  // on the face, in the module frame (straight hinge); x < 0 lies on the tail

  friend bool operator==(const ConnectorSpec&, const ConnectorSpec&) = default;
};

struct IrSpec {
  Face face = Face::kFront;
  Vec3 position{};      // ray origin on the face, in the module frame
  double range = 0.15;  // beyond this the sensor sees nothing

  friend bool operator==(const IrSpec&, const IrSpec&) = default;
};

struct ModuleKind {
  std::string name;
  BodySpec body;
  bool has_wheels = true;
  WheelSpec wheels;
  HingeSpec hinge;
  std::vector<ConnectorSpec> connectors;
  std::vector<IrSpec> ir;  // one per face at most

  friend bool operator==(const ModuleKind&, const ModuleKind&) = default;
};

// The module: a cube about 10 cm wide (10 x 10 x 8 cm, 0.44 kg with its wheels) that
// drives alone on two wheels, a hinge across its middle that bends it, a connector at the centre
// of each face and an IR sensor (15 cm) beside each connector.
ModuleKind standard_kind();

// A longer module without wheels (16 x 10 x 8 cm, 0.6 kg): it moves only by its hinge or when
// docked to others. The same four faces, connectors and IR, placed by the same rules.
ModuleKind long_kind();

// The height of the module frame's origin above the floor when the module stands at rest.
double rest_height(const ModuleKind& kind);

// An empty string when the kind is usable, else what is wrong with it (a size or mass not
// positive, a hinge range the wrong way round, two connectors with one name, ...).
std::string check(const ModuleKind& kind);

}  // namespace symb::sim::mujoco
