// LocalRadio: a simulated short-range radio shared by the robots of one world, the medium that
// swarm algorithms (mEDEA: evo/medea_task.hpp) broadcast over. Each robot has a RadioTask on its
// own node, an IO stream like any other: a message with bytes (io::Bytes) that a task hooked to
// the radio sends it is TRANSMITTED; the radio hands it to the medium, and at the next world step
// the medium delivers it to the RadioTask of every OTHER robot whose centre is within `range` cm
// of the sender's (positions after that step), which SENDS it on to whatever is hooked to it.
//
// A delivered message carries the bytes (the same shared blob, no copy) and one number, the
// sender's robot index, so a receiver can tell senders apart (mEDEA keeps one genome per sender).
//
// Like a real radio it has a bandwidth: per step a robot transmits at most ONE message, the newest
// handed to it since the last step (older ones are counted as overwritten). Deterministic: at a
// step, senders in robot index order, each to its receivers in index order; a receiver's queue
// that is full refuses the message (counted as dropped). Walls do not block the radio (range only).
//
// The medium is a world-runner observer (attach()); positions come from the runner's StepRecord.
// A step finds each sender's receivers on a spatial grid of the positions (spatial_grid.hpp), cells
// as wide as the range: its cost grows with the messages and the robots in range of their senders,
// not with the square of the swarm (out_of_range is counted, not enumerated).
// A world split over processes (hil_split_world.hpp) carries the radio to robots whose nodes run
// elsewhere: the world's medium hands what it delivers to such a robot to a relay() instead of a
// radio task, and puts what the robot sent on air with transmit(); in the robot's process a medium
// that never steps holds the robot's radio task, take_pending() takes what it sent and deliver()
// posts what the world's medium delivered, as step() posts it.
// Lifetime: the LocalRadio must outlive the runner it is attached to and every RadioTask made from
// it (declare it before the ScenarioSession). Thread-safe: tasks and the runner may run on
// different threads (ThreadExecutor). Transmitting touches only the robot's own slot (its own
// mutex, pending message and counters, on its own cache line), so robots' nodes running in
// parallel transmit without contending; step(), connecting and counts() take the medium's lock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "symb/io/bytes.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/sim/spatial_grid.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::os {
class Node;
}

namespace symb::sim {

struct LocalRadioOptions {
  double range = 50;                          // cm, centre to centre
  std::size_t max_message_bytes = 64 * 1024;  // longer messages are refused (counted)
};

struct RadioCounts {
  std::uint64_t transmitted = 0;   // messages that went on air (at most one per robot per step)
  std::uint64_t overwritten = 0;   // replaced by a newer one before their step came
  std::uint64_t too_long = 0;      // refused: longer than max_message_bytes, or no bytes at all
  std::uint64_t delivered = 0;     // (message, receiver) pairs put in a receiver's queue
  std::uint64_t out_of_range = 0;  // (message, other robot) pairs farther than range
  std::uint64_t dropped = 0;       // in range but not delivered: no radio task, or a full queue
};

class LocalRadio;

// The radio device of one robot, as a task. Port 0 in (from hooked tasks): bytes to transmit.
// Port 0 out: bytes received, numbers = {sender robot index}. Messages without bytes are ignored.
class RadioTask final : public os::Task {
 public:
  RadioTask(LocalRadio& radio, std::size_t robot) : radio_(radio), robot_(robot) {}

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_stop() override;

 private:
  LocalRadio& radio_;
  const std::size_t robot_;
};

class LocalRadio {
 public:
  // Fails for a range that is not finite and positive, or no robots.
  static kernel::Result<std::unique_ptr<LocalRadio>> create(std::size_t robots, LocalRadioOptions options = {});
  LocalRadio(const LocalRadio&) = delete;
  LocalRadio& operator=(const LocalRadio&) = delete;

  // Observes `runner`'s steps: from now on every step delivers what was transmitted before it.
  void attach(WorldRunner& runner);
  // Creates robot `robot`'s RadioTask on `node` under `name`, its queue large enough for every
  // other robot's message of a few steps, up to kMaxQueue messages (a robot hears at most about
  // 100 Thymios at once in the default range; beyond the queue, messages are dropped and counted).
  // Does not hook it.
  kernel::Result<os::TaskId> add_to(os::Node& node, std::size_t robot, std::string name = "radio");

  // The medium's step: delivers the pending messages using the robots' positions in `record`.
  // attach() calls it from the runner; tests may call it directly.
  void step(const StepRecord& record);

  static constexpr std::size_t kMaxQueue = 128;

  // What the medium delivers to robot `robot` (a robot whose node runs in another process) goes to
  // `relay` from now on, in step()'s order, on step()'s thread, instead of to a radio task: the
  // sender's index and the bytes; it returns whether it took them (counted delivered, else
  // dropped). Called under the medium's lock: it must not call back into the medium.
  using Relay = std::function<bool(std::size_t sender, const std::shared_ptr<const os::Blob>& bytes)>;
  void relay(std::size_t robot, Relay relay);
  // Robot `robot`'s message for the next step, as its radio task hands one over when a hooked task
  // sends it: refused (too_long) without io::Bytes or beyond max_message_bytes; a newer one
  // overwrites it until the step.
  void transmit(std::size_t robot, std::shared_ptr<const os::Blob> blob);
  // Takes robot `robot`'s message waiting for the next step (null when none), for a medium in
  // another process to put on air.
  std::shared_ptr<const os::Blob> take_pending(std::size_t robot);
  // Posts into robot `robot`'s radio task what another process's medium delivered to it from
  // `sender`, as step() posts (at the node's time; counted delivered, or dropped when the robot
  // has no radio task or its queue is full). Returns whether it was delivered.
  bool deliver(std::size_t robot, std::size_t sender, std::shared_ptr<const os::Blob> blob);

  std::size_t robot_count() const { return robots_.size(); }
  const LocalRadioOptions& options() const { return options_; }
  RadioCounts counts() const;
  // Messages robot `robot`'s radio task received (delivered to its queue) so far.
  std::uint64_t received_by(std::size_t robot) const;

 private:
  friend class RadioTask;
  LocalRadio(std::size_t robots, LocalRadioOptions options) : options_(options), robots_(robots), slots_(robots) {}
  void connect(std::size_t robot, os::Node* node, os::TaskId task);
  void disconnect(std::size_t robot, os::TaskId task);
  // Delivers `m` to `receiver`, under mu_: its relay, or its radio task.
  void deliver_locked(std::size_t receiver, std::size_t sender, os::Message& m);
  // Appends to receivers_ the robots in range of `sender`, in index order.
  void find_receivers(std::size_t sender);

  struct Robot {               // guarded by mu_
    os::Node* node = nullptr;  // while its radio task runs
    os::TaskId task;
    Relay relay;  // set: its node is in another process
    std::uint64_t received = 0;
  };
  // What transmit() touches, guarded by its own mutex: one robot's node never waits for another's.
  struct alignas(64) Slot {
    mutable std::mutex mu;
    std::shared_ptr<const os::Blob> pending;  // to go on air at the next step
    std::uint64_t overwritten = 0;
    std::uint64_t too_long = 0;
  };

  const LocalRadioOptions options_;
  mutable std::mutex mu_;  // before any Slot::mu when both are held
  std::vector<Robot> robots_;
  std::vector<Slot> slots_;
  RadioCounts counts_;  // transmitted, delivered, out_of_range, dropped (the rest is in slots_)
  // Scratch of step(), under mu_: positions and their grid; the robots without a finite position,
  // which every sender tests one by one (a NaN distance is not out of range); messages taken;
  // the receivers of one sender.
  std::vector<Pose> positions_;
  SpatialGrid grid_;
  std::vector<std::size_t> strays_;
  std::vector<std::shared_ptr<const os::Blob>> outgoing_;
  std::vector<std::size_t> receivers_;
};

}  // namespace symb::sim
