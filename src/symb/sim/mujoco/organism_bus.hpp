// OrganismBus: the wired bus of docked modules (the paper's "common bus system" of an organism),
// simulated CAN-like, and the remote hooks that ride it (io/remote_hook.hpp: two proxies and two
// local hooks per remote hook; the bytes on the bus are real io frames).
//
// Topology: the modules are the bus addresses; the connected components of the docking graph
// (who is docked to whom, MujocoWorld::docked_to) are the bus segments. attach() reads it at once
// and after every runner tick (an observer), so a latch or an unlatch is seen at the end of the
// runner tick it happened in (a dock and undock within one tick is not seen at all).
//
// Timing, exact in integer nanoseconds of virtual time: per segment one frame is on the wire at a
// time. When the wire is free, the highest-priority frame queued in any module of the segment
// wins (the remote hook's HookOptions::priority, higher first; then the lower remote hook id, as
// a lower CAN id wins arbitration; then the older frame), and occupies the wire for
//   wire_time = ceil(8 * frame bytes * 1e9 / bandwidth) ns,
// the frame's bytes being its whole encoded io frame (io::hook_frame_wire_bytes: 26 + 4 numbers
// bytes). It reaches the receiver's inbound proxy `latency` after its last bit left. A frame
// offered to an idle segment starts at once. The bus wakes at those instants exactly: it is an
// activity of the executor whose next tick is set to the next event (under the virtual-time
// executor to the nanosecond; under threads as the wall clock allows).
//
// Transmit queue: per module at most `tx_queue_frames` frames wait. When it is full, a frame that
// would win arbitration against the worst queued frame takes that one's place (the worst is
// dropped); otherwise the new frame is refused; either way counted HookDrop::kQueueFull to its
// own hook. So a low-priority flood never locks a higher-priority hook out. Memory is bounded by
// modules x tx_queue_frames.
//
// Link down: when the ends of a remote hook are no longer in one segment, its frames still queued,
// on the wire or within the latency are dropped (HookDrop::kLinkDown), its state becomes kDown
// with a warning in both nodes' logs, and its sends while down are dropped (kLinkDown) at once:
// nothing waits for a link that may never come back. When a dock joins them again, the state
// returns to kUp (logged) and the hook carries again.
//
// Lifetime: the nodes must outlive the bus; the bus must outlive the runner it is attached to
// (declare it before the runner). Destroying the bus removes every remote hook's proxies.
// Thread-safe: proxies, the runner and the bus's own activity may run on different threads.
//
//   kernel::VirtualTimeExecutor ex;   // world, nodes (one per module), then:
//   auto bus = OrganismBus::create(ex, nodes, {.bandwidth = 1e6, .latency = 100us}).value();
//   MujocoRunner runner(ex, world);
//   bus->attach(runner);
//   auto id = bus->hook(0, "osc", 1, "osc", {.port = 1});
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/hook_bus.hpp"
#include "symb/io/remote_hook.hpp"
#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/ids.hpp"
#include "symb/shell/shell.hpp"

namespace symb::os {
class Node;
}

namespace symb::sim::mujoco {

class MujocoRunner;
class MujocoWorld;

struct OrganismBusOptions {
  double bandwidth = 1e6;                                    // bit/s (CAN's top rate)
  kernel::Duration latency = std::chrono::microseconds(50);  // last bit sent to frame delivered
  std::size_t tx_queue_frames = 64;                          // per module
  std::size_t inbound_queue = 64;                            // each inbound proxy's queue
};

// The remote hook's handle, state and description are the HookBus's (io/hook_bus.hpp).
using io::LinkState;
using io::RemoteHookId;
using io::RemoteHookInfo;

struct OrganismBusCounts {
  std::uint64_t frames = 0;      // frames that finished their transmission
  std::uint64_t bits = 0;        // their bits
  kernel::Duration busy{0};      // summed wire time of those frames, over every segment
  std::uint64_t links_down = 0;  // remote hook state changes to down
  std::uint64_t links_up = 0;    // ... and back up
};

class OrganismBus final : public io::HookBus, private io::HookMedium {
 public:
  // `nodes`: one per module, in module order, none null. Fails for a bandwidth that is not a
  // positive finite number, a negative latency, a zero queue, or no nodes.
  static kernel::Result<std::unique_ptr<OrganismBus>> create(kernel::Executor& executor, std::vector<os::Node*> nodes,
                                                             OrganismBusOptions options = {});
  ~OrganismBus() override;
  OrganismBus(const OrganismBus&) = delete;
  OrganismBus& operator=(const OrganismBus&) = delete;

  // Reads the docking topology now and after every tick of `runner`. Once.
  void attach(MujocoRunner& runner);
  // Sets the segments from `world`'s docking state (attach() calls it; a test without a runner
  // may call it directly, on the executor's context).
  void update_topology(const MujocoWorld& world);

  // Hooks task `sender` on module `sender_module` to task `receiver` on `receiver_module`.
  // `options`: the port filter, enabled flag and queue policy make the local hook sender ->
  // outbound proxy; the priority is also the frames' priority on the bus; the policy and the
  // suppression window (with the priority) make the local hook inbound proxy -> receiver, so
  // subsumption works at the receiver as for a local hook. The proxies are named
  // "bus_to.m2.osc.<id>" and "bus_from.m1.osc.<id>" on their nodes. Fails, with a message naming
  // both ends ("remote hook m1/osc -> m2/osc: no task 'osc' on m2"), for a bad module or task, a
  // hook within one module (use a local hook), or the same sender, receiver and port twice. A
  // scenario adds its file's location in front.
  kernel::Result<RemoteHookId> hook(std::size_t sender_module, std::string_view sender, std::size_t receiver_module,
                                    std::string_view receiver, os::HookOptions options = {});
  // "m1/osc" style names: the module by its node's name.
  kernel::Result<RemoteHookId> hook(std::string_view sender, std::string_view receiver,
                                    os::HookOptions options = {}) override;
  // Removes both proxies; messages in them are counted as the local hooks count them.
  kernel::Status unhook(RemoteHookId id) override;

  std::optional<RemoteHookInfo> info(RemoteHookId id) const;
  std::vector<RemoteHookInfo> hooks() const override;
  // The remote hooks as a text table (a shell's `hooks` appends it).
  std::string listing() const override;
  // Lets a module's shell make remote hooks (`hook osc m2/osc --port 1`, the sender on the shell's
  // own node) and list them (`hooks`). The shell must not outlive the bus.
  void serve_shell(shell::Shell::Options& options);

  std::size_t module_count() const { return modules_.size(); }
  // Whether the two modules are on one segment now.
  bool linked(std::size_t a, std::size_t b) const;
  // Module `m`'s segment: the lowest module index in it.
  std::size_t segment_of(std::size_t m) const;
  const OrganismBusOptions& options() const { return options_; }
  OrganismBusCounts counts() const;
  // Wire time of a frame carrying `numbers` numbers.
  kernel::Duration wire_time(std::size_t numbers) const;

 private:
  struct Frame {
    std::uint32_t hook = 0;
    int priority = 0;
    std::uint64_t order = 0;  // submission order, for arbitration ties
    std::size_t from = 0, to = 0;
    kernel::Duration wire{0};
    std::size_t bits = 0;
    std::shared_ptr<const os::Blob> bytes;
    kernel::Time done{0};  // end of transmission, then delivery time
  };
  struct Remote {
    RemoteHookInfo info;  // books filled on demand
    os::TaskId sender, receiver, outbound, inbound;
    os::HookId out_hook, in_hook;
  };
  class Timer;

  OrganismBus(kernel::Executor& executor, std::vector<os::Node*> nodes, OrganismBusOptions options);
  io::HookMedium& medium() { return *this; }
  void transmit(std::uint32_t hook, std::span<const std::byte> frame, std::size_t numbers) override;
  void refuse(std::uint32_t hook, io::HookDrop cause) override;

  // Under mu_: handles every event up to `now`, then sets the timer to the next one.
  void advance_locked(kernel::Time now);
  // Whether `a` wins arbitration against `b`.
  static bool beats(const Frame& a, const Frame& b);
  void start_next_locked(std::size_t segment, kernel::Time at);
  bool segment_busy_locked(std::size_t segment) const;
  void arm_locked(kernel::Time now);
  void set_labels_locked(std::vector<std::size_t> labels, kernel::Time now);
  void drop_locked(Frame& f, io::HookDrop cause);
  Remote* find_locked(std::uint32_t hook);
  RemoteHookInfo fill(const Remote& r) const;
  void on_timer();
  kernel::Time now() const;

  kernel::Executor& executor_;
  const OrganismBusOptions options_;
  std::vector<os::Node*> modules_;
  std::unique_ptr<Timer> timer_;
  bool attached_ = false;

  mutable std::mutex mu_;
  std::vector<std::size_t> label_;     // per module: its segment
  std::vector<std::deque<Frame>> tx_;  // per module
  std::vector<Frame> on_wire_;         // at most one per segment
  std::deque<Frame> propagating_;      // off the wire, within the latency, by time
  std::vector<Remote> remotes_;
  std::uint32_t next_id_ = 1;
  std::uint64_t order_ = 0;
  kernel::Time armed_{-1};  // the instant the timer is set for (kTimeNever: not set)
  OrganismBusCounts counts_;
};

}  // namespace symb::sim::mujoco
