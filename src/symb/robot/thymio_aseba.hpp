// AsebaThymio: a real Thymio II (or one of Aseba Playground's simulated ones) as the robot layer's
// devices, over an Aseba link (io/aseba_link.hpp). It gives the same two devices a simulated
// Thymio has, with the same channels and units, so the same device tasks (`ir`: a SensorTask,
// `wheels`: an ActuatorSinkTask with its watchdog) and the same controllers run on it unchanged:
//
//   ir      7 channels ir0..ir6, raw, [0, kIrMax]: prox.horizontal, read every control period.
//           The robot's raw values are the simulation's units: Enki's Thymio2 model (which the
//           simulator's IrModel follows) was fitted to them, 0 = nothing seen, about 4500 at
//           contact; values above kIrMax are clamped (docs/thymio.md).
//   ground  2 channels left, right, reflectance [0, 1]: prox.ground.reflected / 1023, read with
//           the IR (a simulated robot's `ground` task is made only when a hook names it; so here)
//   wheels  2 channels left, right, Thymio motor units, [-500, 500]: written to
//           motor.left.target / motor.right.target at once, multiplied by `speed_scale`
//           (1 for Playground, whose 500 is the simulation's 16.6 cm/s; 16.6/20 for a real
//           robot, whose 500 is about 20 cm/s, to keep a controller's speeds in cm/s).
//
// A thread of its own (a driver's, like a serial reader) reads the robot each control period:
// one get variables for prox.horizontal and the measured wheel speeds (one block when they lie
// close together, as on a Thymio), published to `ir` as an interrupt would, stamped with the
// steady clock's time (since its epoch) at which it was asked for. The wheel speeds give odometry
// (pose and path length, integrated over the read intervals).
//
// Link loss: a read error, the end of the stream, or `lost_periods` unanswered reads in a row.
// When it notices, it marks the link down, counts a stop and tries to write zero targets (it
// reaches a robot whose link is only congested; a robot whose cable is out keeps its last target
// until the link returns, which no host can change), reports the loss, closes the stream, and from
// then on refuses wheel commands (each counted as the actuator's driver error) and publishes
// nothing, so the controller falls silent and the wheels task's watchdog stops too. It reopens the
// stream with backoff (io::ReopenBackoff), discovers the node again, checks its description is
// still a Thymio's, writes zero targets before anything else, and reports the return.
//
// A node whose description lacks prox.horizontal (7 words) or the motor targets (1 word each) is
// not a Thymio: connect() fails naming what is missing or has the wrong size.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "symb/io/aseba_link.hpp"
#include "symb/io/reopen_backoff.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/syslog.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/sensor.hpp"

namespace symb::robot::thymio {

// Where a Thymio keeps what the backend reads and writes (variable addresses from its description).
struct AsebaLayout {
  std::uint16_t prox_horizontal = 0;  // 7 words
  std::uint16_t motor_left_target = 0;
  std::uint16_t motor_right_target = 0;
  std::optional<std::uint16_t> prox_ground_reflected;  // 2 words (when present)
  std::optional<std::uint16_t> motor_left_speed;       // measured speeds, for odometry (when present)
  std::optional<std::uint16_t> motor_right_speed;
};
// The layout of a Thymio II's description, or an error naming every variable that is missing or
// has the wrong size ("node 1 'e-puck' is not a Thymio II: no prox.horizontal (7 words), ...").
kernel::Result<AsebaLayout> thymio_layout(const io::aseba::NodeDescription& d);

// Speed units per cm/s. Aseba Playground's Thymio (Enki) turns 500 into 16.6 cm/s, as the
// simulation does; a real Thymio II's 500 is about 20 cm/s (docs/thymio.md).
inline constexpr double kPlaygroundCmPerSecondPerUnit = 16.6 / 500.0;
inline constexpr double kRealCmPerSecondPerUnit = 20.0 / 500.0;
inline constexpr double kWheelBase = 9.4;  // cm, between the wheels' contact points
// prox.ground.reflected's full scale (a 10-bit reading): reflectance = raw / this.
inline constexpr double kGroundFullScale = 1023.0;

struct AsebaThymioOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  // How long one read waits for its answer; unanswered reads in a row before the link is lost.
  kernel::Duration reply_timeout = std::chrono::milliseconds(30);
  int lost_periods = 3;
  kernel::Duration connect_timeout = std::chrono::seconds(2);
  kernel::Duration reopen_first = std::chrono::milliseconds(100);
  kernel::Duration reopen_most = std::chrono::seconds(2);
  double speed_scale = 1.0;                            // motor target = wheel command x this
  double cm_per_unit = kPlaygroundCmPerSecondPerUnit;  // for odometry from measured speeds
};

struct AsebaThymioStats {
  io::aseba::LinkStats link;        // every connection's, since the backend was made
  std::uint64_t samples = 0;        // IR samples published
  std::uint64_t missed_reads = 0;   // reads not answered in time
  std::uint64_t wheel_writes = 0;   // wheel commands written to the robot
  std::uint64_t wheel_refused = 0;  // wheel commands while the link was down
  std::uint64_t losses = 0;         // times the link was lost
  std::uint64_t reconnects = 0;     // times it came back
  std::uint64_t stops = 0;          // zero targets applied (at each loss and each reconnect)
  bool up = false;
  std::uint16_t node = 0;
  std::string node_name;
  kernel::Duration last_stop_delay{0};             // from noticing the last loss to the wheels' stop
  kernel::Duration last_round_trip{0};             // of the newest read: get variables sent to its answer
  std::int16_t left_target = 0, right_target = 0;  // what the robot was last told
  // Odometry from the measured wheel speeds (cm, cm, rad; cm).
  double x = 0, y = 0, heading = 0, path = 0;
};

class AsebaThymio : public std::enable_shared_from_this<AsebaThymio> {
 public:
  using Reporter = std::function<void(os::LogLevel, std::string_view)>;

  static std::shared_ptr<AsebaThymio> create(std::shared_ptr<io::IOStream> stream, AsebaThymioOptions options = {});
  ~AsebaThymio();
  AsebaThymio(const AsebaThymio&) = delete;
  AsebaThymio& operator=(const AsebaThymio&) = delete;

  // Where link losses, returns and refusals are told (set before connect()); any thread.
  void on_report(Reporter r);
  // Opens the stream when needed, finds the node and checks it is a Thymio. An error names what
  // failed (nothing answered, not a Thymio, ...).
  kernel::Status connect();
  // Starts and stops the reading thread. After stop() wheel commands are refused and zero
  // targets are written when the robot can be reached.
  void start();
  void stop();

  std::shared_ptr<Sensor> ir() const { return ir_; }
  std::shared_ptr<Sensor> ground() const { return ground_; }
  std::shared_ptr<Actuator> wheels() const { return wheels_; }
  io::aseba::AsebaLink& link() { return link_; }
  AsebaThymioStats stats() const;
  const AsebaThymioOptions& options() const { return options_; }

  // Internal (the wheels actuator): writes one command, in Thymio units.
  kernel::Status write_wheels(float left, float right);

 private:
  AsebaThymio(std::shared_ptr<io::IOStream> stream, AsebaThymioOptions options);
  void run();
  void read_once();
  void lose(const std::string& why);
  void try_reconnect();
  kernel::Status handshake();
  kernel::Status write_targets(std::int16_t left, std::int16_t right);
  kernel::Status write_targets_locked(std::int16_t left, std::int16_t right);  // write_mu_ held
  void report(os::LogLevel level, const std::string& text);
  kernel::Time now() const;

  AsebaThymioOptions options_;
  io::aseba::AsebaLink link_;
  std::shared_ptr<Sensor> ir_;
  std::shared_ptr<Sensor> ground_;
  std::shared_ptr<Actuator> wheels_;

  // Orders the target writes: the stop a loss writes comes after any command already on its way,
  // and a command that waited for it sees the link down. Taken before mu_, never inside it.
  std::mutex write_mu_;
  mutable std::mutex mu_;  // everything below
  std::condition_variable cv_;
  Reporter reporter_;
  std::optional<io::aseba::NodeDescription> node_;
  AsebaLayout layout_;
  std::uint16_t block_start_ = 0, block_count_ = 0;
  AsebaThymioStats stats_;
  bool stopping_ = false;
  // The reading thread's own (connect() runs before it starts).
  int misses_ = 0;
  std::optional<kernel::Time> last_read_;
  io::ReopenBackoff backoff_;  // the reading thread's
  std::thread thread_;
};

}  // namespace symb::robot::thymio
