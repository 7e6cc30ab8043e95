// DdsBus: remote hooks between processes and machines, carried by Eclipse Cyclone DDS (Debian
// cyclonedds-dev, its C API). The second HookBus (io/hook_bus.hpp) beside the organism bus, with
// the same books (io/remote_hook.hpp), and no task of its own on a message's way:
//
//   sender --hook to an os::HookSink--> DDS writer  ==DDS==>  listener --Node::send_as(dds_from.<id>)
//          --local hook--> receiver
//
// The sender's hook (port filter, inhibition) hands each message to the DDS writer on the
// sender's own thread, within its send(); the reader's listener, on DDS's thread, sends it as the
// stand-in task dds_from.<id>, whose local hook to the receiver applies the receiver's rules
// (priority, queue policy, suppression window) and counts it, straight into the receiver's queue.
//
// Every process of a run makes one DdsBus over its own nodes and declares the same remote hooks
// ("r1/osc" -> "r2/osc"): each process builds the ends whose nodes it holds (the sender's end: a
// DDS writer and the sender's hook to it; the receiver's end: a DDS reader, the stand-in and its
// hook to the receiver) and ignores the others. Peers find each other by DDS discovery, with no
// configuration.
//
// On the wire, following ROS 2's DDS conventions so a ROS 2 tool sees the topics:
//   topic  rt/<prefix>/<sender node>/<sender task>/to/<receiver node>/<receiver task>[/port<p>]
//   type   symb::msg::dds_::HookFrame_  (io/dds/HookFrame.idl, compiled by idlc at build time)
// one topic per remote hook, reliable, keep-all, volatile, automatic liveliness with a lease.
//
// What is counted, never silent (DdsBusCounts, and each hook's books):
// - at the sender: blobs refused (kBlob), sends while no reader of the hook is matched
//   (kLinkDown: nothing waits for a peer that may never come), writes DDS refused (kQueueFull);
// - at the receiver: serials are per origin (one sending end), so a gap is counted `lost` (in
//   transit); samples that are garbage (more than 32 numbers, a port the hook does not carry, a
//   hook field naming another hook, a serial going backwards) are counted by cause, logged with
//   what was wrong, and dropped; the receiver's bounded queue takes a flood under the hook's
//   policy, what it refuses or overwrites counted (kReceiver).
// - a sending end that disappears (its process killed) is noticed by DDS liveliness within the
//   lease: the hook turns kDown with a warning in the receiver's log, counted `peers_lost`; the
//   rest of the run goes on. A sender whose readers are all gone turns kDown too.
// Books of a hook with both ends in one process close as the organism bus's do:
//   attempted == delivered + dropped + in_flight. A hook split over two processes closes over the
//   two processes' books together: sender.written == receiver.received + receiver.lost once the
//   traffic has settled (tests/io/dds_bus_test.cpp checks both).
//
// Threads: DDS calls the listeners on its own threads (and on a writer's, for a reader in the
// same process); they send through Node::inject, which the thread executor runs at once and the
// virtual-time executor on its own context. No node lock is held while DDS is called, nor the
// bus's lock while a node's are taken.
//
//   auto bus = DdsBus::create({&r2}, {.domain = 7, .prefix = "demo"}).value();  // in process 2
//   auto id = bus->hook("r1/osc", "r2/osc", {.port = 1}).value();
//   bus->wait_linked(std::chrono::seconds(5));
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "symb/io/hook_bus.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::os {
class Node;
}

namespace symb::io {

struct DdsBusOptions {
  std::uint32_t domain = 0;     // DDS domain id (0..232); a test picks its own so runs do not meet
  std::string prefix = "symb";  // the first name of every topic: rt/<prefix>/...
  kernel::Duration lease = std::chrono::milliseconds(1000);  // a silent sender is lost after it
};

struct DdsBusCounts {
  std::uint64_t written = 0;       // samples written by this process's sending ends
  std::uint64_t received = 0;      // valid samples taken by this process's receiving ends
  std::uint64_t lost = 0;          // serial gaps: written by a peer, never arrived
  std::uint64_t bad_size = 0;      // garbage: more numbers than a message carries
  std::uint64_t bad_port = 0;      // garbage: a port the hook does not carry
  std::uint64_t unknown_hook = 0;  // garbage: a sample naming another hook than its topic's
  std::uint64_t out_of_order = 0;  // garbage: a serial at or before one already taken
  std::uint64_t peers_lost = 0;    // sending ends that stopped asserting liveliness (killed, cut off)
  std::uint64_t peers_back = 0;    // ... and came back
  std::uint64_t peers_left = 0;    // sending ends that left cleanly (their writer deleted)
  std::uint64_t garbage() const { return bad_size + bad_port + unknown_hook + out_of_order; }
};

class DdsBus final : public HookBus {
 public:
  struct Core;  // shared with DDS's listener threads (defined in the .cpp)
  struct End;
  struct ListenerArg;
  class Writer;
  // `nodes`: this process's nodes, none null, unique names; they must outlive the bus. The first
  // bus of a process on a domain makes the domain (with a participant lease of three liveliness
  // leases) and deletes it when it goes, taking any other participant on it along: a second bus
  // or a raw participant on the same domain must go first. Fails when
  // DDS cannot make a participant on the domain (the DDS error text), for a domain above 232 or an
  // empty prefix.
  static kernel::Result<std::unique_ptr<DdsBus>> create(std::vector<os::Node*> nodes, DdsBusOptions options = {});
  ~DdsBus() override;
  DdsBus(const DdsBus&) = delete;
  DdsBus& operator=(const DdsBus&) = delete;

  // HookBus. `sender`, `receiver`: "node/task". The ends on this process's nodes are built (their
  // tasks must exist), the others are left to their processes; fails when neither node is here.
  kernel::Result<RemoteHookId> hook(std::string_view sender, std::string_view receiver,
                                    os::HookOptions options = {}) override;
  kernel::Status unhook(RemoteHookId id) override;
  std::vector<RemoteHookInfo> hooks() const override;
  std::string listing() const override;

  // The DDS topic of a remote hook (see above).
  std::string topic(std::string_view sender, std::string_view receiver, int port) const;
  // Waits (polling, up to `timeout`) until every end built here is matched: each writer with a
  // reader, each reader with a live writer. False on timeout.
  bool wait_linked(kernel::Duration timeout) const;
  // Waits (up to `timeout`) until every reader has acknowledged every sample written here; a
  // process calls it before it exits so that its last messages are not lost with it.
  bool flush(kernel::Duration timeout) const;
  // Deletes the writers of the sending ends built here (their books stay): their readers see
  // them leave (peers_left), which tells a peer that this process sent all it will send. Further
  // sends are dropped as kLinkDown. A process that ends calls flush(), then this.
  void finish_sending();
  // Per remote hook, DDS's part of the books: what this process's end wrote, took and found
  // missing. A hook split over two processes closes as sender.written == receiver.received +
  // receiver.lost once both finished.
  struct HookCounts {
    RemoteHookId id;
    std::string key;  // the HookFrame_'s hook field
    std::uint64_t written = 0, received = 0, lost = 0;
  };
  std::vector<HookCounts> hook_counts() const;
  DdsBusCounts counts() const;
  const DdsBusOptions& options() const { return options_; }

 private:
  DdsBus(std::vector<os::Node*> nodes, DdsBusOptions options);

  const DdsBusOptions options_;
  std::vector<os::Node*> nodes_;
  std::shared_ptr<Core> core_;  // shared with work injected into the nodes and the writers, which may outlive a hook
};

}  // namespace symb::io
