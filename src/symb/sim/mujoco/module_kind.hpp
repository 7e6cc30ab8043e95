// ModuleKind: what one kind of robot module is made of, as plain data (the paper's bodies,
// actuators, connectors and sensors). A kind is the model; the 3D world (mujoco_world.hpp) holds
// the running state. Two kinds differ only in their numbers: nothing about a kind lives in code.
//
// Beside its kind's sensors every module has an IMU on its front half (mujoco_world.hpp) and
// touch on its four faces, which need no data.
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
#include <cstddef>
#include <numbers>
#include <optional>
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
  // Velocity servo, N*m per rad/s of speed error. 0.05 brings a standard module to 98.3% of a
  // commanded 0.1 m/s on the floor (98.8% of 0.15 m/s; the wheels sink about 0.3 mm into the soft
  // contact, which makes their rolling radius that much smaller); with the wheel's rotor inertia
  // (2e-4 kg*m^2) it stays a quarter of what Euler's explicit 2 ms step can carry (0.2).
  double gain = 0.05;

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

// A laser scanner: `rays` horizontal rays (in the module frame) from one point on a face, spread
// evenly over `field_of_view` centred on the face's outward normal, ray 0 the rightmost (clockwise
// end) and the last the leftmost, as a ROS LaserScan from angle_min to angle_max. One ray looks
// straight out. Each ray reads the distance to the first thing it meets that is not its own
// module, or `range` when that is beyond it.
inline constexpr std::size_t kMaxLaserRays = 32;  // one message's inline numbers (os::Payload)
struct LaserSpec {
  Face face = Face::kFront;
  Vec3 position{};                          // the rays' origin, on the face
  std::size_t rays = 15;                    // 1..kMaxLaserRays
  double field_of_view = std::numbers::pi;  // rad, (0, 2 pi]; ignored for one ray
  double range = 1.0;                       // m

  friend bool operator==(const LaserSpec&, const LaserSpec&) = default;
};

// A small camera without a renderer: a pinhole on a face looking along its outward normal, one
// ray per pixel. Pixel (column u, row v), row 0 at the top and column 0 at the left, looks along
// f * out + (width / 2 - u - 0.5) * left + (height / 2 - v - 0.5) * up, with f = (width / 2) /
// tan(field_of_view / 2) (square pixels: the vertical field follows from the aspect). Each pixel
// reads the distance along its ray to the first thing it meets that is not its own module (or
// `range`) and that thing's object id (mujoco_world.hpp: module index + 1, an obstacle's negative
// id, 0 for the floor or nothing).
inline constexpr std::size_t kMaxCameraWidth = 160;
inline constexpr std::size_t kMaxCameraHeight = 120;
struct CameraSpec {
  Face face = Face::kFront;
  Vec3 position{};  // the pinhole, on the face
  std::size_t width = 32;
  std::size_t height = 24;
  double field_of_view = std::numbers::pi / 3;  // rad, horizontal, (0, 170 degrees]
  double range = 2.0;                           // m

  friend bool operator==(const CameraSpec&, const CameraSpec&) = default;
};

struct ModuleKind {
  std::string name;
  BodySpec body;
  bool has_wheels = true;
  WheelSpec wheels;
  HingeSpec hinge;
  std::vector<ConnectorSpec> connectors;
  std::vector<IrSpec> ir;  // one per face at most
  std::optional<LaserSpec> laser;
  std::optional<CameraSpec> camera;

  friend bool operator==(const ModuleKind&, const ModuleKind&) = default;
};

// The module: a cube about 10 cm wide (10 x 10 x 8 cm, 0.44 kg with its wheels) that
// drives alone on two wheels, a hinge across its middle that bends it, a connector at the centre
// of each face and an IR sensor (15 cm) beside each connector.
ModuleKind standard_kind();

// A longer module without wheels (16 x 10 x 8 cm, 0.6 kg): it moves only by its hinge or when
// docked to others. The same four faces, connectors and IR, placed by the same rules.
ModuleKind long_kind();

// The standard module with a camera (32 x 24 pixels, 60 degrees, 2 m) on its front face above
// the IR sensor, and a laser scanner (15 rays over 180 degrees, 1 m) below the connector: the
// "camera module" of the issue, a kind that differs from the cube only in its data.
ModuleKind camera_kind();

// The largest field of view a camera may have (rad, 170 degrees): a pinhole cannot see 180.
inline constexpr double kMaxCameraFieldOfView = 170.0 * std::numbers::pi / 180.0;

// The height of the module frame's origin above the floor when the module stands at rest.
double rest_height(const ModuleKind& kind);

// An empty string when the kind is usable, else what is wrong with it (a size or mass not
// positive, a hinge range the wrong way round, two connectors with one name, ...).
std::string check(const ModuleKind& kind);

}  // namespace symb::sim::mujoco
