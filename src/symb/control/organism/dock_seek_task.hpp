// DockSeekTask: the swarm controller of self-assembly (paper section VI-A, "from swarm to
// organism"). A free module steers its front connector onto the docking beacon of the nearest
// open, undocked back connector of another module (the connector device's beacon channels), and
// latches when the connector reads aligned, close and face to face. A free module keeps its own
// back connector closed, so no other seeker takes it for a target; once docked it opens its back,
// so the chain grows from its tail (docs/organism.md "Self-assembly").
//
// DockSeeker is the steering itself, pure and deterministic (its randomness is drawn by the
// caller), so its phases are tested with synthetic readings:
//   search    no beacon: spin on the spot for `search_spin`, then drive a little with a random turn;
//   approach  go to the pre-dock point `predock` m out along the target's normal;
//   align     turn on the spot until face to face;
//   dock      creep in along the normal; back to approach when off the line;
//   back off  reverse and turn for a while when the front IR sees something nearer than the
//             target (another seeker), or when stuck (neither the beacon nor the gyro shows any
//             motion for `stuck_time` while commanded to move).
//
//   in  from the task `connector` (default connector_front): [state, open, peer, beacon distance,
//       bearing, heading] (the 3D connector device's reading); from `ir`: 4 proximities, front
//       first (0..1, 1 - d / ir_range); from `imu`: 6 channels, gyro z the last
//   out port 0: wheels [left, right] in Thymio units (-500..500, 500 = max_speed)
// Probe "dock_seek": [phase, v m/s, w rad/s, beacon distance].
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "symb/io/device.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control::organism {

struct DockSeekOptions {
  std::string connector = "connector_front";  // the seeking connector: its sensor task and device
  std::string back = "connector_back";        // the device closed while free, opened once docked
  std::string ir = "ir";
  std::string imu = "imu";
  double predock = 0.25;      // m: the pre-dock point's distance from the target, along its normal
  double axle = 0.05;         // m: the wheel axle behind the seeking connector
  double half_track = 0.055;  // m: half the distance between the wheels (steering gain included)
  double max_speed = 0.15;    // m/s: what 500 Thymio units mean
  double ir_range = 0.15;     // m: the IR sensor's range (proximity 0 there)
  kernel::Duration search_spin = std::chrono::seconds(10);
  kernel::Duration search_drive = std::chrono::seconds(2);
  kernel::Duration stuck_time = std::chrono::seconds(2);
  kernel::Duration backoff_time = std::chrono::milliseconds(1800);
};

enum class SeekPhase : std::uint8_t { kSearch, kApproach, kAlign, kDock, kBackOff, kDocked };
inline constexpr std::array<const char*, 6> kSeekPhaseNames = {"search", "approach", "align",
                                                               "dock",   "back-off", "docked"};

struct SeekInput {
  int state = 0;                   // 0 free, 1 aligned, 2 docked
  double distance = -1;            // beacon, m; < 0 none
  double bearing = 0;              // rad
  double heading = 0;              // rad
  std::optional<double> front_ir;  // m to the nearest thing ahead, when within range
  double gyro_z = 0;               // rad/s
};

struct SeekOutput {
  double v = 0, w = 0;  // m/s, rad/s
  bool latch = false;   // try to latch now
};

class DockSeeker {
 public:
  explicit DockSeeker(DockSeekOptions o = {}) : o_(std::move(o)) {}
  // One control step of `dt` seconds. `wander` in [-1, 1]: the turn of the next search drive,
  // drawn by the caller (used only when a search drive starts).
  SeekOutput step(const SeekInput& in, double dt, double wander);
  SeekPhase phase() const { return phase_; }
  // The wheel rim speeds (m/s) of (v, w), scaled down together so neither exceeds max_speed.
  std::array<double, 2> wheels(const SeekOutput& out) const;

 private:
  DockSeekOptions o_;
  SeekPhase phase_ = SeekPhase::kSearch;
  SeekPhase resume_ = SeekPhase::kSearch;  // the phase a back-off returns to
  double in_phase_ = 0;                    // s in the current search cycle or back-off
  double backoff_speed_ = -0.07;           // m/s
  double backoff_turn_ = 1;
  double wander_ = 0;
  double search_turn_ = 1;  // rad/s while scanning
  int behind_turn_ = 0;     // the side turned to while the pre-dock point is behind, 0 none
  // Stuck detection: motion seen in the current window.
  double window_ = 0, turned_ = 0, last_distance_ = -1, window_distance_ = -1;
  bool commanded_ = false;
};

struct DockSeekStats {
  std::uint64_t readings = 0, ignored = 0, latches = 0, refused = 0;
};

class DockSeekTask : public os::Task {
 public:
  using DeviceLookup = std::function<std::shared_ptr<io::Device>(std::string_view)>;
  DockSeekTask(DockSeekOptions options, DeviceLookup devices);
  DockSeekStats stats() const;
  SeekPhase phase() const { return static_cast<SeekPhase>(phase_.load(std::memory_order_relaxed)); }

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;

 private:
  kernel::Status ioctl(const std::string& device, const std::string& command);
  DockSeekOptions o_;
  DeviceLookup devices_;
  DockSeeker seeker_;
  SeekInput in_;
  std::optional<kernel::Time> last_tick_;
  bool back_opened_ = false;
  std::atomic<int> phase_{0};
  os::WarningLimiter warning_;
  struct Counters {
    kernel::Counter readings, ignored, latches, refused;
  } counters_;
};

}  // namespace symb::control::organism
