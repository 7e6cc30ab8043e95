// HookBus: what carries hooks between nodes that do not share a queue, seen from the user. A
// remote hook joins task `sender` on one node to task `receiver` on another ("m1/osc" ->
// "m2/osc"); its messages keep the hook's semantics (port filter, priority, queue policy,
// suppression window at the receiver) and its books close:
//   attempted == delivered + dropped (by cause) + in flight   (io::RemoteHookBooks)
// Two buses implement it: the organism bus of docked modules, simulated in process
// (sim/mujoco/organism_bus.hpp), and the DDS bus between processes and machines
// (io/dds/dds_bus.hpp). Code that makes, lists or removes remote hooks through this interface
// (a scenario, a shell, a test) runs unchanged over either. Both keep a remote hook's books the
// same way (io/remote_hook.hpp). The organism bus builds one of two local hooks and two proxy
// tasks around a HookMedium; the DDS bus, between processes where each hand-off between threads
// shows in the latency, of a hook to an os::HookSink that writes on the sender's thread and a
// stand-in task its reader's listener sends as (os::Node::send_as) into the receiver's queue.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/remote_hook.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/hook.hpp"

namespace symb::io {

// A remote hook's handle: never reused, so a handle kept past its unhook matches nothing.
struct RemoteHookId {
  std::uint32_t value = 0;
  bool valid() const { return value != 0; }
  friend bool operator==(RemoteHookId, RemoteHookId) = default;
};

enum class LinkState { kUp, kDown };
inline const char* to_string(LinkState state) { return state == LinkState::kUp ? "up" : "down"; }

struct RemoteHookInfo {
  RemoteHookId id;
  std::size_t sender_module = 0;    // index of the sender's node among the bus's local nodes
  std::size_t receiver_module = 0;  // (a bus between processes: kRemoteEnd when on another process)
  std::string sender;               // "m1/osc"
  std::string receiver;             // "m2/osc"
  os::HookOptions options;
  LinkState state = LinkState::kUp;
  RemoteHookBooks books;  // of the ends this process holds (see the bus for a split hook)
  MediumBooks medium;
};

// A module index meaning "this end lives in another process".
inline constexpr std::size_t kRemoteEnd = static_cast<std::size_t>(-1);

class HookBus {
 public:
  virtual ~HookBus() = default;
  // Hooks "node/task" `sender` to "node/task" `receiver`. Fails with a message naming both ends.
  virtual kernel::Result<RemoteHookId> hook(std::string_view sender, std::string_view receiver,
                                            os::HookOptions options = {}) = 0;
  // Removes the hook's proxies; messages in them are counted as the local hooks count them.
  virtual kernel::Status unhook(RemoteHookId id) = 0;
  virtual std::vector<RemoteHookInfo> hooks() const = 0;
  // The remote hooks as a text table (a shell's `hooks` appends it).
  virtual std::string listing() const = 0;
};

}  // namespace symb::io
