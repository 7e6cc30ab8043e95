// MujocoWorld: the 3D world of robot modules on MuJoCo 2.2.2. It owns the compiled model and its
// running state, steps them by whole 2 ms steps, takes each module's wheel speeds and hinge
// target, gives its hinge angle and speed, its IR range per face, its IMU, the force on each
// face, its laser scan and camera image, and its pose, and docks modules by their connectors at
// runtime.
//
// Sensors, all computed from the state at the end of the last step():
//   imu      the front half's (the base's) specific force, m/s^2 (what an accelerometer reads:
//            the acceleration minus gravity, so +9.81 up at rest), averaged over the last step()
//            call from the change of its speed; and its angular velocity, rad/s, at that instant;
//            both in the module frame.
//   touch    per face, the normal force (N) of the contacts on the body's two box halves whose
//            normal in the module frame is mostly along that face's normal; contacts mostly
//            vertical (the floor under a module without wheels) count on no face.
//   laser, camera: ray casts (module_kind.hpp says which rays), skipping the module's own bodies.
// Object ids, what the camera reports per pixel: module m is m + 1, obstacle k is -(k + 1), the
// floor and nothing are 0.
//
// Docking. Each connector has an open flag (set by its owner; open by default) and a state:
//   free     not docked, and no other module's undocked connector faces it within the tolerances;
//   aligned  not docked, and one does (latching it would succeed if both are open);
//   docked   welded to another module's connector.
// latch(m, c) looks for the other module's connector nearest to c. It succeeds only when both are
// open and undocked, their centres lie within kLatchPositionTolerance of each other and their
// outward normals are opposite within kLatchAngleTolerance; then a spare weld of the model is
// retargeted to the two bodies, given their current relative pose (so nothing jumps) and switched
// on. Otherwise it is refused, and the error says which bound failed and by how much. unlatch
// switches the weld off and returns it to the pool. Every latch, unlatch and refusal is appended
// to the docking log with the step, the time, both connectors and the measured distance and angle.
//
// Handles: modules and connectors are indices (the order of the specs, the order of the kind's
// connectors), never pointers. A handle out of range is a programming error: std::out_of_range.
// Nothing is global but one thing MuJoCo owns: its warning printer, switched off once for the
// process (mujoco_world.cpp says why). The same specs and the same calls give the same run bit for
// bit. A world moves but does not copy; use it from one thread at a time.
//
// Divergence: MuJoCo, on finding a bad acceleration, resets its state (time included) and only
// counts a warning. step() checks those counters after every substep: on a bad position, speed or
// acceleration, or a full constraint or contact buffer, it stops and returns the error, and every
// later step() refuses. It loops on step counts, never on MuJoCo's time.
//
//   auto made = MujocoWorld::make({{"a", standard_kind(), {0, 0, 0}},
//                                  {"b", standard_kind(), {0.11, 0, std::numbers::pi}}});
//   if (!made) return report(made.error());
//   MujocoWorld& world = made.value();
//   world.set_hinge_target(0, 0.3);
//   if (auto s = world.latch(0, *world.find_connector(0, "front")); !s) report(s.error());
//   if (auto s = world.step(500); !s) report(s.error());  // one simulated second
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/mjcf_model.hpp"
#include "symb/sim/mujoco/module_kind.hpp"

struct mjData_;

namespace symb::sim::mujoco {

// Two connectors latch only when their centres are at most this far apart (m): about what a
// mechanical docking guide of a 10 cm module draws in.
inline constexpr double kLatchPositionTolerance = 0.015;
// ... and their outward normals are opposite within this angle (rad, 10 degrees).
inline constexpr double kLatchAngleTolerance = 10.0 * std::numbers::pi / 180.0;

inline constexpr std::size_t kNoIndex = static_cast<std::size_t>(-1);

enum class ConnectorState { kFree, kAligned, kDocked };

// The docking beacon (real modules dock with IR beacons that give a bearing). A connector sees
// the nearest *suitable* connector of another module: open, undocked, on the opposite face (a
// front sees backs, a left sees rights), within kBeaconRange of it, within kBeaconCone of its
// own outward normal, and with the looking connector within kBeaconFaceCone of that target's
// normal (the target's emitter shines out of its face). The figures are the ones the
// self-assembly exploration worked with (docs/organism.md "Self-assembly").
inline constexpr double kBeaconRange = 1.0;                         // m
inline constexpr double kBeaconCone = 0.6 * std::numbers::pi;       // rad either side (108 deg)
inline constexpr double kBeaconFaceCone = 0.45 * std::numbers::pi;  // rad either side (81 deg)
struct Beacon {
  double distance = 0;            // m, between the two connectors' centres (horizontal)
  double bearing = 0;             // rad, CCW +, from my outward normal to the target's centre
  double heading = 0;             // rad, from my outward normal to the target's reversed normal (0: face to face)
  std::size_t module = kNoIndex;  // what is seen (for tests and logs; a real beacon would not say)
  std::size_t connector = kNoIndex;
};
const char* state_name(ConnectorState state);

struct Pose3 {
  Vec3 position{};                                  // of the module frame's origin, world frame
  std::array<double, 4> quaternion = {1, 0, 0, 0};  // w, x, y, z: module frame to world
  double yaw() const;                               // heading about z, rad
};

inline constexpr int kNothingId = 0;  // the floor, or nothing within range
constexpr int module_object_id(std::size_t module) { return static_cast<int>(module) + 1; }
constexpr int obstacle_object_id(std::size_t obstacle) { return -static_cast<int>(obstacle) - 1; }

struct ImuReading {
  Vec3 acceleration{};      // specific force, m/s^2, module frame
  Vec3 angular_velocity{};  // rad/s, module frame
};

enum class DockChange { kLatched, kUnlatched, kRefused };
const char* change_name(DockChange change);

struct DockEvent {
  std::uint64_t step = 0;
  double time = 0;  // s
  DockChange change = DockChange::kRefused;
  std::size_t module = kNoIndex;  // the one asked to latch or unlatch
  std::size_t connector = kNoIndex;
  std::size_t other_module = kNoIndex;  // the partner, when there was one
  std::size_t other_connector = kNoIndex;
  double distance = -1;  // m between the connectors' centres, when measured
  double angle = -1;     // rad between one's normal and the other's reversed, when measured
  std::string reason;    // for a refusal, why; else which weld
};

class MujocoWorld {
 public:
  // Builds the model text, compiles it from memory and computes the first instant; or why not.
  static kernel::Result<MujocoWorld> make(std::vector<ModuleSpec> modules, ModelOptions options = {});

  MujocoWorld(MujocoWorld&&) noexcept;
  MujocoWorld& operator=(MujocoWorld&&) noexcept;
  ~MujocoWorld();

  const std::string& mjcf() const;  // the model's text, for MuJoCo's own viewer
  std::size_t module_count() const;
  // The model's degrees of freedom (MuJoCo's nv): 9 for a wheeled module, 7 without wheels. From
  // 60 on, MuJoCo 2.2.2 solves with sparse matrices instead of dense ones.
  std::size_t degrees_of_freedom() const;
  const ModuleSpec& module(std::size_t module) const;
  std::optional<std::size_t> find_module(std::string_view name) const;
  std::optional<std::size_t> find_connector(std::size_t module, std::string_view name) const;

  // Advances by `substeps` steps of kTimestep. An error on divergence (see above); the world is
  // then failed and stays so. Afterwards every reading describes the new instant.
  kernel::Status step(std::uint64_t substeps);
  std::uint64_t steps() const;
  double time() const;  // steps() * kTimestep, s
  bool failed() const;

  // Rim speeds in m/s, clamped to the kind's max_speed; act from the next step on. An error for a
  // module without wheels.
  kernel::Status set_wheels(std::size_t module, double left, double right);
  // The hinge's position servo target, rad, clamped to the kind's range.
  void set_hinge_target(std::size_t module, double angle);
  double hinge_angle(std::size_t module) const;  // rad
  double hinge_speed(std::size_t module) const;  // rad/s
  Pose3 pose(std::size_t module) const;
  // Puts the module at rest at `where` on the floor (its hinge keeps its angle), as a person sets
  // a robot down or takes it away. Refused while any of its connectors is docked.
  kernel::Status place(std::size_t module, const StartPose& where);
  // The distance (m) from the face's IR sensor to the first thing its ray meets that is not the
  // module itself, or nothing when that is beyond the sensor's range or the face has no sensor.
  std::optional<double> ir(std::size_t module, Face face) const;
  ImuReading imu(std::size_t module) const;
  // The normal force on each face, N, in kFaces order.
  std::array<double, 4> touch(std::size_t module) const;
  // The kind's laser scan, one distance (m) per ray, its range where a ray meets nothing.
  // std::invalid_argument when the kind has no laser or `distances` is not one per ray.
  void laser(std::size_t module, std::span<float> distances) const;
  // The kind's camera image, row by row from the top: per pixel the distance (m, its range for
  // nothing) and the object id. std::invalid_argument when the kind has no camera or a span is not
  // width x height.
  void camera(std::size_t module, std::span<float> depth, std::span<std::int32_t> ids) const;
  std::size_t obstacle_count() const;

  Vec3 connector_position(std::size_t module, std::size_t connector) const;  // world frame
  Vec3 connector_normal(std::size_t module, std::size_t connector) const;    // outward, unit
  void set_open(std::size_t module, std::size_t connector, bool open);
  bool is_open(std::size_t module, std::size_t connector) const;
  ConnectorState connector_state(std::size_t module, std::size_t connector) const;
  // The connector this one is docked to, as {module, connector}; nothing when not docked.
  std::optional<std::pair<std::size_t, std::size_t>> docked_to(std::size_t module, std::size_t connector) const;

  // What this connector's beacon receiver sees (above), or nothing.
  std::optional<Beacon> beacon(std::size_t module, std::size_t connector) const;

  kernel::Status latch(std::size_t module, std::size_t connector);
  kernel::Status unlatch(std::size_t module, std::size_t connector);
  const std::vector<DockEvent>& docking_log() const;
  std::size_t spare_welds_free() const;

  // MuJoCo 2.2.2's scratch stack, in numbers (mjtNum, 8 bytes each): what the model reserves
  // (nstack, sized by mjcf_model.cpp) and the most any step has used so far (maxuse_stack).
  std::size_t stack_reserved() const;
  std::size_t stack_peak() const;

 private:
  struct State;
  explicit MujocoWorld(std::unique_ptr<State> state);
  std::unique_ptr<State> s_;
};

}  // namespace symb::sim::mujoco
