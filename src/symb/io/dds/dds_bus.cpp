#include "symb/io/dds/dds_bus.hpp"

#include <algorithm>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include <dds/dds.h>

#include "symb/io/dds/dds_participant.hpp"
#include "symb/kernel/executor.hpp"
#include "symb/os/node.hpp"

#include "HookFrame.h"

namespace symb::io {
namespace {

constexpr int kTakeBatch = 32;
constexpr std::uint64_t kLoggedPerCause = 3;  // garbage of one cause logged per hook; the rest counted

std::string dds_error(dds_return_t rc) { return dds::error_text(rc); }
using dds::topic_part;

struct Name {
  std::string_view node, task;
};

// Stands on the receiver's node for a sender in another process: the listener sends as it
// (Node::send_as), so the local hook from it to the receiver applies and counts. It never runs a
// handler of its own.
class RemoteSenderStandIn final : public os::Task {};

}  // namespace

// What a DDS listener is given: its end's id, and the lock that keeps one reader's deliveries in
// the order they were taken should DDS call its listener from two threads.
struct DdsBus::ListenerArg {
  Core* core = nullptr;
  std::uint32_t id = 0;
  std::mutex deliver;
};

// The sending end's far end of the sender's hook (os::HookSink): writes each message the hook lets
// through to DDS on the sender's own thread, within its send().
class DdsBus::Writer final : public os::HookSink {
 public:
  Writer(std::string name, std::weak_ptr<Core> core, std::uint32_t id, std::string key)
      : HookSink(std::move(name)), core_(std::move(core)), id_(id), key_(std::move(key)) {}
  void on_message(const os::Message& m) override;

 private:
  const std::weak_ptr<Core> core_;
  const std::uint32_t id_;
  const std::string key_;  // the sample's `hook` field
  std::mutex write_mu_;    // serials in the order they are written
};

// One remote hook as this process holds it: its sending end, its receiving end, or both.
struct DdsBus::End {
  RemoteHookInfo info;
  std::string key;  // the HookFrame_'s `hook` field: "r1/osc>r2/osc" (":<port>" with a filter)
  // Sending end.
  os::Node* sn = nullptr;
  os::TaskId sender;
  os::HookId out_hook;  // sender -> the Writer (a hook to an os::HookSink)
  dds_entity_t writer = 0;
  std::uint64_t origin = 0;
  std::uint32_t serial = 0;
  bool matched = false;  // a reader of the hook is matched
  std::uint64_t written = 0;
  // Receiving end.
  os::Node* rn = nullptr;
  os::TaskId receiver, inbound;  // inbound: the RemoteSenderStandIn
  os::HookId in_hook;            // inbound -> receiver
  dds_entity_t reader = 0;
  std::map<std::uint64_t, std::uint32_t> next;  // per origin: the serial expected next
  std::uint32_t alive = 0;                      // live writers (liveliness)
  std::uint64_t received = 0, lost = 0;
  std::uint64_t pending = 0;              // taken from DDS, not yet sent on by the stand-in
  std::array<std::uint64_t, 4> logged{};  // garbage logged, by cause
  dds_entity_t topic = 0;
  std::unique_ptr<ListenerArg> arg;  // the listeners' argument
  bool sending() const { return sn != nullptr; }
  bool receiving() const { return rn != nullptr; }
};

struct DdsBus::Core {
  std::mutex mu;
  std::vector<std::unique_ptr<End>> ends;
  DdsBusCounts counts;
  std::uint32_t next_id = 1;
  std::uint64_t origin_base = 0;
  dds_entity_t participant = 0;
  dds_entity_t domain = 0;   // made by this bus (else another bus of the process made it)
  std::weak_ptr<Core> self;  // work injected into a node finds the core only while the bus lives

  End* find_locked(std::uint32_t id) {
    for (auto& e : ends)
      if (e->info.id.value == id) return e.get();
    return nullptr;
  }
};

namespace {

// Logs on a node's own context (the listeners run on DDS's threads).
void log_on(os::Node* node, bool warn, std::string text) {
  node->inject([node, warn, text = std::move(text)] {
    if (warn)
      node->log().warn("dds", text);
    else
      node->log().info("dds", text);
  });
}

using ListenerArg = DdsBus::ListenerArg;

// Takes what DDS holds for a receiving end, checks each sample, counts it, and has the stand-in
// send the good ones on to the receiver: on this listener thread under the thread executor (its
// inject() runs at once), so a message reaches the receiver's queue with no thread between. An
// idle receiver then handles it on this thread too (kernel::RunWakesHere), as a raw DDS program
// answers in its listener; its handler runs after this listener's locks are released, so that
// it may write to DDS and be delivered to on this thread.
void on_data(dds_entity_t reader, void* arg) {
  auto* a = static_cast<ListenerArg*>(arg);
  DdsBus::Core& core = *a->core;
  const kernel::RunWakesHere here;
  std::lock_guard order(a->deliver);
  std::vector<std::pair<os::Port, os::Payload>> posts;
  std::vector<std::string> warnings;
  os::Node* node = nullptr;
  os::TaskId inbound;
  {
    std::lock_guard lock(core.mu);
    DdsBus::End* e = core.find_locked(a->id);
    void* samples[kTakeBatch];
    dds_sample_info_t infos[kTakeBatch];
    for (;;) {
      samples[0] = nullptr;
      const int n = dds_take(reader, samples, infos, kTakeBatch, kTakeBatch);
      if (n <= 0) break;
      for (int i = 0; i < n && e != nullptr; ++i) {
        if (!infos[i].valid_data) continue;
        const auto& s = *static_cast<const symb_msg_dds__HookFrame_*>(samples[i]);
        auto garbage = [&](std::size_t cause, std::uint64_t& count, std::string what) {
          ++count;
          if (e->logged[cause]++ < kLoggedPerCause)
            warnings.push_back("hook " + e->key + ": dropped a sample from origin " + std::to_string(s.origin) + ": " +
                               what + (e->logged[cause] == kLoggedPerCause ? " (further ones counted only)" : ""));
        };
        if (s.hook == nullptr || e->key != s.hook) {
          garbage(0, core.counts.unknown_hook,
                  "it names hook '" + std::string(s.hook ? s.hook : "") + "', not this topic's");
          continue;
        }
        if (s.values._length > os::Payload::kInlineValues) {
          garbage(
              1, core.counts.bad_size,
              std::to_string(s.values._length) + " numbers, more than " + std::to_string(os::Payload::kInlineValues));
          continue;
        }
        if (e->info.options.port >= 0 && s.port != e->info.options.port) {
          garbage(2, core.counts.bad_port,
                  "port " + std::to_string(s.port) + ", the hook carries port " + std::to_string(e->info.options.port) +
                      " only");
          continue;
        }
        auto [it, fresh] = e->next.try_emplace(s.origin, 0);
        if (s.serial < it->second) {
          garbage(3, core.counts.out_of_order,
                  "serial " + std::to_string(s.serial) + " after " + std::to_string(it->second - 1));
          continue;
        }
        const std::uint64_t gap = s.serial - it->second;
        if (gap > 0) {
          e->lost += gap;
          core.counts.lost += gap;
          warnings.push_back("hook " + e->key + ": " + std::to_string(gap) +
                             " message(s) lost in transit before serial " + std::to_string(s.serial));
        }
        it->second = s.serial + 1;
        ++e->received;
        ++core.counts.received;
        ++e->pending;
        posts.emplace_back(s.port, os::Payload(std::span<const float>(s.values._buffer, s.values._length)));
      }
      dds_return_loan(reader, samples, n);
      // Less than a batch: DDS held no more. A sample that arrives now calls this listener again.
      if (n < kTakeBatch) break;
    }
    if (e == nullptr) return;
    node = e->rn;
    inbound = e->inbound;
  }
  for (std::string& w : warnings) log_on(node, true, std::move(w));
  if (posts.empty()) return;
  // Outside the core's lock: sending takes the receiving node's locks, and a Writer (on a
  // sender's thread, within its node's send) takes the core's.
  node->inject([weak = core.self, node, inbound, id = a->id, posts = std::move(posts)] {
    const auto alive = weak.lock();
    if (!alive) return;  // the bus is gone, and its stand-ins with it
    // A stand-in removed meanwhile (unhook) refuses; its end, and its books, are gone too.
    for (const auto& [port, payload] : posts) (void)node->send_as(inbound, port, payload);
    std::lock_guard lock(alive->mu);
    if (DdsBus::End* e = alive->find_locked(id)) e->pending -= posts.size();
  });
}

// A status listener's frame: runs `f(core, end, text)` under the core's lock for the listener's end
// (nothing when the end is gone); `f` answers the node to warn and sets `text` to the warning.
template <class F>
void on_end(void* arg, F f) {
  auto* a = static_cast<ListenerArg*>(arg);
  std::string text;
  os::Node* node = nullptr;
  {
    std::lock_guard lock(a->core->mu);
    DdsBus::End* e = a->core->find_locked(a->id);
    if (e == nullptr) return;
    node = f(*a->core, *e, text);
  }
  if (!text.empty()) log_on(node, true, std::move(text));
}

void on_liveliness(dds_entity_t, const dds_liveliness_changed_status_t status, void* arg) {
  on_end(arg, [&](DdsBus::Core& core, DdsBus::End& e, std::string& text) {
    e.alive = status.alive_count;
    if (status.not_alive_count_change > 0) {  // the lease ran out: killed, hung or cut off
      core.counts.peers_lost += static_cast<std::uint64_t>(status.not_alive_count_change);
      e.info.state = LinkState::kDown;
      text = "hook " + e.key + ": its sender is gone (no liveliness within the lease); the run goes on";
    } else if (status.alive_count_change < 0) {  // it left cleanly (its writer was deleted)
      ++core.counts.peers_left;
      if (status.alive_count == 0) e.info.state = LinkState::kDown;
    } else if (status.alive_count_change > 0 && e.info.state == LinkState::kDown && core.counts.peers_lost > 0) {
      ++core.counts.peers_back;
      e.info.state = LinkState::kUp;
      text = "hook " + e.key + ": its sender is back";
    } else if (status.alive_count > 0) {
      e.info.state = LinkState::kUp;
    }
    return e.rn;
  });
}

void on_matched(dds_entity_t, const dds_publication_matched_status_t status, void* arg) {
  on_end(arg, [&](DdsBus::Core&, DdsBus::End& e, std::string& text) {
    const bool was = e.matched;
    e.matched = status.current_count > 0;
    if (was && !e.matched) {
      e.info.state = LinkState::kDown;
      text = "hook " + e.key + ": no reader left; sends are dropped as link_down until one comes";
    } else if (!was && e.matched && !e.receiving()) {
      e.info.state = LinkState::kUp;
    }
    return e.sn;
  });
}

void on_sample_lost(dds_entity_t, const dds_sample_lost_status_t status, void* arg) {
  on_end(arg, [&](DdsBus::Core& core, DdsBus::End& e, std::string&) {
    core.counts.lost += static_cast<std::uint64_t>(status.total_count_change);
    e.lost += static_cast<std::uint64_t>(status.total_count_change);
    return e.rn;
  });
}

}  // namespace

DdsBus::DdsBus(std::vector<os::Node*> nodes, DdsBusOptions options)
    : options_(std::move(options)), nodes_(std::move(nodes)), core_(std::make_shared<Core>()) {}

kernel::Result<std::unique_ptr<DdsBus>> DdsBus::create(std::vector<os::Node*> nodes, DdsBusOptions options) {
  if (options.domain > dds::kMaxDomain)
    return kernel::Error{"dds bus: domain " + std::to_string(options.domain) + " is above " +
                         std::to_string(dds::kMaxDomain)};
  if (options.prefix.empty()) return kernel::Error{"dds bus: empty topic prefix"};
  if (options.lease <= kernel::Duration{0}) return kernel::Error{"dds bus: the liveliness lease must be positive"};
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i] == nullptr) return kernel::Error{"dds bus: node " + std::to_string(i) + " is null"};
    for (std::size_t j = 0; j < i; ++j)
      if (nodes[j]->name() == nodes[i]->name())
        return kernel::Error{"dds bus: two nodes named '" + nodes[i]->name() + "'"};
  }
  std::unique_ptr<DdsBus> bus(new DdsBus(std::move(nodes), std::move(options)));
  // The participant's lease (dds_participant.hpp) bounds how long a killed peer's readers stay
  // matched; set once per process and domain; a second bus on the domain shares the first one's.
  auto p = dds::open_participant(bus->options_.domain, bus->options_.lease, "dds bus");
  if (!p) return kernel::Error{p.error()};
  bus->core_->domain = p->domain;
  bus->core_->participant = p->participant;
  bus->core_->self = bus->core_;
  // An origin tells one sending end's serials from another's (a restarted process, a second
  // writer on a topic); it must differ across processes, so it does not come from a seed.
  std::random_device rd;
  bus->core_->origin_base = (static_cast<std::uint64_t>(rd()) << 32) ^ rd();
  return bus;
}

DdsBus::~DdsBus() {
  std::vector<std::unique_ptr<End>> ends;
  {
    std::lock_guard lock(core_->mu);
    ends.swap(core_->ends);
  }
  for (auto& e : ends) {
    if (e->sending()) (void)e->sn->unhook(e->out_hook);
    if (e->receiving()) (void)e->rn->remove(e->inbound);
  }
  // Deleting the participant deletes every reader and writer and waits for running listeners.
  if (core_->participant > 0) dds_delete(core_->participant);
  if (core_->domain > 0) dds_delete(core_->domain);
}

bool DdsBus::flush(kernel::Duration timeout) const {
  std::vector<dds_entity_t> writers;
  {
    std::lock_guard lock(core_->mu);
    for (const auto& e : core_->ends)
      if (e->writer > 0) writers.push_back(e->writer);
  }
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (const dds_entity_t w : writers) {
    const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(until - std::chrono::steady_clock::now());
    if (dds_wait_for_acks(w, std::max<std::int64_t>(left.count(), 0)) != DDS_RETCODE_OK) return false;
  }
  return true;
}

std::string DdsBus::topic(std::string_view sender, std::string_view receiver, int port) const {
  const auto part = [](std::string_view name) {
    const auto slash = name.find('/');
    return topic_part(name.substr(0, slash)) + "/" + topic_part(name.substr(slash + 1));
  };
  return "rt/" + topic_part(options_.prefix) + "/" + part(sender) + "/to/" + part(receiver) +
         (port >= 0 ? "/port" + std::to_string(port) : "");
}

kernel::Result<RemoteHookId> DdsBus::hook(std::string_view sender, std::string_view receiver, os::HookOptions options) {
  const std::string what = "remote hook " + std::string(sender) + " -> " + std::string(receiver);
  auto split = [&](std::string_view name, Name& out, std::size_t& module) -> kernel::Status {
    const auto slash = name.find('/');
    if (slash == std::string_view::npos || slash == 0 || slash + 1 == name.size() ||
        name.find('/', slash + 1) != std::string_view::npos)
      return kernel::Error{what + ": '" + std::string(name) + "' is not of the form node/task"};
    out = {name.substr(0, slash), name.substr(slash + 1)};
    module = kRemoteEnd;
    for (std::size_t m = 0; m < nodes_.size(); ++m)
      if (nodes_[m]->name() == out.node) module = m;
    return {};
  };
  Name sname, rname;
  std::size_t sm = kRemoteEnd, rm = kRemoteEnd;
  if (auto s = split(sender, sname, sm); !s) return kernel::Error{s.error()};
  if (auto s = split(receiver, rname, rm); !s) return kernel::Error{s.error()};
  if (sm == kRemoteEnd && rm == kRemoteEnd) {
    std::string known;
    for (const os::Node* node : nodes_) known += (known.empty() ? "" : ", ") + node->name();
    return kernel::Error{what + ": neither end is on this process (its nodes: " + known + ")"};
  }
  if (sm != kRemoteEnd && sm == rm) return kernel::Error{what + ": both ends on one node; use a local hook"};
  std::optional<os::TaskId> s, r;
  if (sm != kRemoteEnd) {
    s = nodes_[sm]->find(sname.task);
    if (!s) return kernel::Error{what + ": no task '" + std::string(sname.task) + "' on " + nodes_[sm]->name()};
  }
  if (rm != kRemoteEnd) {
    r = nodes_[rm]->find(rname.task);
    if (!r) return kernel::Error{what + ": no task '" + std::string(rname.task) + "' on " + nodes_[rm]->name()};
  }
  const std::string key =
      std::string(sender) + ">" + std::string(receiver) + (options.port >= 0 ? ":" + std::to_string(options.port) : "");
  std::uint32_t id = 0;
  {
    std::lock_guard lock(core_->mu);
    for (const auto& o : core_->ends)
      if (o->key == key)
        return kernel::Error{what + ": already hooked on that port (remote hook " + std::to_string(o->info.id.value) +
                             ")"};
    id = core_->next_id++;
  }
  auto end = std::make_unique<End>();
  end->key = key;
  end->info.id = RemoteHookId{id};
  end->info.sender_module = sm;
  end->info.receiver_module = rm;
  end->info.sender = std::string(sender);
  end->info.receiver = std::string(receiver);
  end->info.options = options;
  end->info.state = LinkState::kDown;  // up once DDS matched the ends
  end->origin = core_->origin_base ^ (0x9E3779B97F4A7C15ull * id);
  end->arg = std::make_unique<ListenerArg>();
  end->arg->core = core_.get();
  end->arg->id = id;

  const std::string name = topic(sender, receiver, options.port);
  end->topic = dds_create_topic(core_->participant, &symb_msg_dds__HookFrame__desc, name.c_str(), nullptr, nullptr);
  if (end->topic < 0) return kernel::Error{what + ": DDS topic " + name + ": " + dds_error(end->topic)};
  dds_qos_t* qos = dds::reliable_qos(options_.lease);
  const auto fail = [&](std::string text) -> kernel::Result<RemoteHookId> {
    dds_delete_qos(qos);
    if (end->writer > 0) dds_delete(end->writer);
    if (end->reader > 0) dds_delete(end->reader);
    dds_delete(end->topic);
    if (end->receiving()) (void)end->rn->remove(end->inbound);
    return kernel::Error{what + ": " + text};
  };
  const std::string suffix = "." + std::to_string(id);
  if (rm != kRemoteEnd) {
    os::Node& rn = *nodes_[rm];
    // Its queue is never used: what it stands for is sent as it, not to it.
    auto inbound =
        rn.create("dds_from" + suffix, std::make_unique<RemoteSenderStandIn>(), os::TaskOptions{.queue_capacity = 1});
    if (!inbound) return fail(inbound.error());
    end->rn = &rn;
    end->receiver = *r;
    end->inbound = *inbound;
    os::HookOptions in_options = options;
    in_options.port = -1;
    auto in_hook = rn.hook(*inbound, *r, in_options);
    if (!in_hook) return fail(in_hook.error());
    end->in_hook = *in_hook;
  }
  if (sm != kRemoteEnd) {
    end->sn = nodes_[sm];
    end->sender = *s;
  }
  End* raw = end.get();
  {
    // Registered before DDS entities exist: their listeners look the end up at once.
    std::lock_guard lock(core_->mu);
    core_->ends.push_back(std::move(end));
  }
  auto unregister = [&](std::string text) {
    std::unique_ptr<End> back;
    {
      std::lock_guard lock(core_->mu);
      auto it = std::find_if(core_->ends.begin(), core_->ends.end(), [&](auto& e) { return e.get() == raw; });
      back = std::move(*it);
      core_->ends.erase(it);
    }
    end = std::move(back);
    return fail(std::move(text));
  };
  if (raw->receiving()) {
    dds_listener_t* l = dds_create_listener(raw->arg.get());
    dds_lset_data_available(l, on_data);
    dds_lset_liveliness_changed(l, on_liveliness);
    dds_lset_sample_lost(l, on_sample_lost);
    const dds_entity_t reader = dds_create_reader(core_->participant, raw->topic, qos, l);
    dds_delete_listener(l);
    if (reader < 0) return unregister("DDS reader: " + dds_error(reader));
    std::lock_guard lock(core_->mu);
    raw->reader = reader;
  }
  if (raw->sending()) {
    dds_listener_t* l = dds_create_listener(raw->arg.get());
    dds_lset_publication_matched(l, on_matched);
    const dds_entity_t writer = dds_create_writer(core_->participant, raw->topic, qos, l);
    dds_delete_listener(l);
    if (writer < 0) return unregister("DDS writer: " + dds_error(writer));
    {
      std::lock_guard lock(core_->mu);
      raw->writer = writer;
    }
    // The suppression window is the receiver's (its end applies it); a sink has no queue.
    os::HookOptions out_options = options;
    out_options.suppress_window = kernel::Duration{0};
    auto out_hook =
        raw->sn->hook(raw->sender, std::make_shared<Writer>("dds_to" + suffix, core_, id, key), out_options);
    if (!out_hook) return unregister(out_hook.error());
    std::lock_guard lock(core_->mu);
    raw->out_hook = *out_hook;
  }
  dds_delete_qos(qos);
  os::Node& logger = raw->sending() ? *raw->sn : *raw->rn;
  logger.log().info("dds", what + ": remote hook " + std::to_string(id) + " on " + name);
  return RemoteHookId{id};
}

kernel::Status DdsBus::unhook(RemoteHookId id) {
  std::unique_ptr<End> gone;
  {
    std::lock_guard lock(core_->mu);
    auto it = std::find_if(core_->ends.begin(), core_->ends.end(), [&](auto& e) { return e->info.id == id; });
    if (it == core_->ends.end()) return kernel::Error{"no remote hook " + std::to_string(id.value)};
    gone = std::move(*it);
    core_->ends.erase(it);
  }
  if (gone->sending() && gone->out_hook.serial != 0) (void)gone->sn->unhook(gone->out_hook);
  if (gone->receiving()) (void)gone->rn->remove(gone->inbound);
  // Waits for the end's running listeners; later ones find no end and do nothing.
  if (gone->writer > 0) dds_delete(gone->writer);
  if (gone->reader > 0) dds_delete(gone->reader);
  dds_delete(gone->topic);
  return {};
}

std::vector<RemoteHookInfo> DdsBus::hooks() const {
  struct Copy {
    RemoteHookInfo info;
    os::Node *sn, *rn;
    os::HookId out_hook, in_hook;
  };
  std::vector<Copy> copies;
  {
    std::lock_guard lock(core_->mu);
    for (const auto& e : core_->ends) {
      Copy c{e->info, e->sn, e->rn, e->out_hook, e->in_hook};
      MediumBooks& m = c.info.medium;
      // Written and not yet taken here (both ends here), or taken and not yet handed on. A
      // sample taken by a listener on the writer's own thread is counted taken before written.
      const std::uint64_t taken = e->received + e->lost;
      const std::uint64_t in_dds = e->sending() && e->receiving() && e->written > taken ? e->written - taken : 0;
      m.link_down += e->lost;
      m.in_medium = in_dds + e->pending;
      copies.push_back(std::move(c));
    }
  }
  auto traffic = [](const os::Node* node, os::HookId id) {
    if (node != nullptr)
      for (const os::HookInfo& h : node->hooks())
        if (h.id == id) return h.accounting;
    return os::HookTraffic{};
  };
  std::vector<RemoteHookInfo> out;
  for (Copy& c : copies) {
    const os::HookTraffic in = traffic(c.rn, c.in_hook);
    // The stand-in holds nothing: what the listener gave it is what it sent.
    c.info.medium.posted = in.sent;
    c.info.books = remote_hook_books(traffic(c.sn, c.out_hook), c.info.medium, in);
    out.push_back(std::move(c.info));
  }
  return out;
}

std::string DdsBus::listing() const {
  std::ostringstream out;
  out << "id  sender -> receiver  port  prio  state  attempted  delivered  dropped  in_flight  written  received  "
         "lost\n";
  const auto counted = hook_counts();
  for (const RemoteHookInfo& h : hooks()) {
    out << h.id.value << "  " << h.sender << " -> " << h.receiver << "  "
        << (h.options.port < 0 ? std::string("any") : std::to_string(h.options.port)) << "  " << h.options.priority
        << "  " << to_string(h.state) << "  " << h.books.attempted << "  " << h.books.delivered << "  "
        << h.books.dropped() << "  " << h.books.in_flight;
    for (const HookCounts& c : counted)
      if (c.id == h.id) out << "  " << c.written << "  " << c.received << "  " << c.lost;
    std::string causes;
    for (std::size_t c = 0; c < h.books.dropped_by.size(); ++c)
      if (h.books.dropped_by[c] > 0)
        causes += (causes.empty() ? "" : ", ") + std::string(to_string(static_cast<HookDrop>(c))) + " " +
                  std::to_string(h.books.dropped_by[c]);
    if (!causes.empty()) out << "  (" << causes << ")";
    out << '\n';
  }
  const DdsBusCounts c = counts();
  out << "dds: written " << c.written << ", received " << c.received << ", lost " << c.lost << ", garbage "
      << c.garbage() << " (size " << c.bad_size << ", port " << c.bad_port << ", hook " << c.unknown_hook << ", order "
      << c.out_of_order << "), peers lost " << c.peers_lost << '\n';
  return out.str();
}

bool DdsBus::wait_linked(kernel::Duration timeout) const {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    bool all = true;
    {
      std::lock_guard lock(core_->mu);
      for (const auto& e : core_->ends) {
        if (e->sending() && !e->matched) all = false;
        if (e->receiving()) {
          dds_subscription_matched_status_t st{};
          if (dds_get_subscription_matched_status(e->reader, &st) < 0 || st.current_count == 0) all = false;
        }
      }
    }
    if (all) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void DdsBus::finish_sending() {
  std::vector<dds_entity_t> writers;
  {
    std::lock_guard lock(core_->mu);
    for (auto& e : core_->ends) {
      if (e->writer <= 0) continue;
      writers.push_back(e->writer);
      e->writer = 0;
      e->matched = false;
      if (!e->receiving() || e->alive == 0) e->info.state = LinkState::kDown;
    }
  }
  for (const dds_entity_t w : writers) dds_delete(w);
}

std::vector<DdsBus::HookCounts> DdsBus::hook_counts() const {
  std::lock_guard lock(core_->mu);
  std::vector<HookCounts> out;
  for (const auto& e : core_->ends) out.push_back({e->info.id, e->key, e->written, e->received, e->lost});
  return out;
}

DdsBusCounts DdsBus::counts() const {
  std::lock_guard lock(core_->mu);
  return core_->counts;
}

void DdsBus::Writer::on_message(const os::Message& m) {
  const auto core = core_.lock();
  if (!core) return;  // the bus is gone (a send counted just before it went)
  std::lock_guard order(write_mu_);
  dds_entity_t writer = 0;
  symb_msg_dds__HookFrame_ s{};
  {
    std::lock_guard lock(core->mu);
    End* e = core->find_locked(id_);
    if (e == nullptr) return;  // unhooked while this message was being sent
    ++e->info.medium.handed;
    if (m.payload.blob) {
      ++e->info.medium.blob;
      return;
    }
    if (!e->matched) {
      ++e->info.medium.link_down;
      return;
    }
    writer = e->writer;
    s.origin = e->origin;
    s.serial = e->serial++;
  }
  s.hook = const_cast<char*>(key_.c_str());
  s.stamp = m.time.count();
  s.port = m.port;
  s.values._length = s.values._maximum = m.payload.count;
  s.values._buffer = const_cast<float*>(m.payload.values);
  s.values._release = false;
  // Outside the core's lock: DDS may deliver to a reader of this process on this thread.
  const dds_return_t rc = dds_write(writer, &s);
  std::lock_guard lock(core->mu);
  End* e = core->find_locked(id_);
  if (e == nullptr) return;
  if (rc == DDS_RETCODE_OK) {
    ++e->written;
    ++core->counts.written;
  } else {
    --e->serial;  // write_mu_: nothing was written after it
    ++e->info.medium.queue_full;
  }
}

}  // namespace symb::io
