#include "symb/sim/mujoco/organism_bus.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <numeric>
#include <sstream>
#include <utility>

#include "symb/io/bytes.hpp"
#include "symb/os/node.hpp"
#include "symb/os/port_layout.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"

namespace symb::sim::mujoco {

// The bus's own activity: ticked once, at the next instant something happens on the bus.
class OrganismBus::Timer final : public kernel::Activity {
 public:
  explicit Timer(OrganismBus& bus) : bus_(bus) {}

  void set_next(kernel::Duration d) {
    std::lock_guard lock(mu_);
    if (slot_ != nullptr) slot_->set_period(d);
  }
  // Detaches and waits until the executor let go (at once under the virtual-time executor outside
  // a run, which is where a bus is destroyed).
  void shutdown() {
    kernel::ActivitySlot* slot = nullptr;
    {
      std::lock_guard lock(mu_);
      slot = slot_;
    }
    if (slot == nullptr) return;
    slot->detach();  // may release at once, which takes mu_
    std::unique_lock lock(mu_);
    cv_.wait(lock, [&] { return released_; });
  }

 private:
  void on_activity_attached(kernel::ActivitySlot& slot) override {
    std::lock_guard lock(mu_);
    slot_ = &slot;
  }
  void on_activity_start() override { bus_.on_timer(); }
  void on_activity_input() override {}
  void on_activity_tick() override { bus_.on_timer(); }
  void on_activity_stop() override {}
  void on_activity_released() override {
    std::lock_guard lock(mu_);
    slot_ = nullptr;
    released_ = true;
    cv_.notify_all();
  }

  OrganismBus& bus_;
  std::mutex mu_;
  std::condition_variable cv_;
  kernel::ActivitySlot* slot_ = nullptr;
  bool released_ = false;
};

kernel::Result<std::unique_ptr<OrganismBus>> OrganismBus::create(kernel::Executor& executor,
                                                                 std::vector<os::Node*> nodes,
                                                                 OrganismBusOptions options) {
  if (nodes.empty()) return kernel::Error{"organism bus: no modules"};
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (nodes[i] == nullptr) return kernel::Error{"organism bus: module " + std::to_string(i) + " has no node"};
  if (!(std::isfinite(options.bandwidth) && options.bandwidth > 0))
    return kernel::Error{"organism bus: the bandwidth must be a positive number of bit/s"};
  if (options.latency.count() < 0) return kernel::Error{"organism bus: the latency must not be negative"};
  if (options.tx_queue_frames == 0 || options.inbound_queue == 0)
    return kernel::Error{"organism bus: the queues must hold at least one frame"};
  auto bus = std::unique_ptr<OrganismBus>(new OrganismBus(executor, std::move(nodes), options));
  executor.attach(*bus->timer_, {.priority = 200, .period = kernel::Duration{0}, .name = "organism_bus"});
  return bus;
}

OrganismBus::OrganismBus(kernel::Executor& executor, std::vector<os::Node*> nodes, OrganismBusOptions options)
    : executor_(executor),
      options_(options),
      modules_(std::move(nodes)),
      timer_(std::make_unique<Timer>(*this)),
      label_(modules_.size()),
      tx_(modules_.size()) {
  std::iota(label_.begin(), label_.end(), std::size_t{0});  // undocked until told otherwise
}

OrganismBus::~OrganismBus() {
  timer_->shutdown();
  std::vector<Remote> remotes;
  {
    std::lock_guard lock(mu_);
    remotes.swap(remotes_);
  }
  for (const Remote& r : remotes) {
    (void)modules_[r.info.sender_module]->remove(r.outbound);
    (void)modules_[r.info.receiver_module]->remove(r.inbound);
  }
  // The proxies call into this object: wait until none runs any more.
  for (os::Node* node : modules_) node->wait_released();
}

kernel::Time OrganismBus::now() const { return executor_.clock().now(); }

void OrganismBus::attach(MujocoRunner& runner) {
  if (attached_) return;
  attached_ = true;
  std::shared_ptr<WorldAccess> access = runner.access();
  auto read = [this, access] { access->with_world([this](MujocoWorld& world) { update_topology(world); }); };
  read();
  runner.add_observer([read](const MujocoStepRecord&) { read(); });
}

void OrganismBus::update_topology(const MujocoWorld& world) {
  const std::size_t n = std::min(modules_.size(), world.module_count());
  std::vector<std::size_t> parent(modules_.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto root = [&](std::size_t m) {
    while (parent[m] != m) m = parent[m] = parent[parent[m]];
    return m;
  };
  for (std::size_t m = 0; m < n; ++m) {
    for (std::size_t c = 0; c < world.module(m).kind.connectors.size(); ++c) {
      const auto other = world.docked_to(m, c);
      if (!other || other->first >= n) continue;
      const std::size_t a = root(m), b = root(other->first);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the lower index stays the root
    }
  }
  std::vector<std::size_t> labels(modules_.size());
  for (std::size_t m = 0; m < labels.size(); ++m) labels[m] = root(m);
  std::lock_guard lock(mu_);
  set_labels_locked(std::move(labels), now());
}

bool OrganismBus::linked(std::size_t a, std::size_t b) const {
  std::lock_guard lock(mu_);
  return label_.at(a) == label_.at(b);
}

std::size_t OrganismBus::segment_of(std::size_t m) const {
  std::lock_guard lock(mu_);
  return label_.at(m);
}

OrganismBusCounts OrganismBus::counts() const {
  std::lock_guard lock(mu_);
  return counts_;
}

kernel::Duration OrganismBus::wire_time(std::size_t numbers) const {
  const double bits = 8.0 * static_cast<double>(io::hook_frame_wire_bytes(numbers));
  return kernel::Duration{static_cast<std::int64_t>(std::ceil(bits * 1e9 / options_.bandwidth))};
}

// --- remote hooks ------------------------------------------------------------------------------

kernel::Result<RemoteHookId> OrganismBus::hook(std::string_view sender, std::string_view receiver,
                                               os::HookOptions options) {
  const std::string what = "remote hook " + std::string(sender) + " -> " + std::string(receiver);
  auto split = [&](std::string_view name, std::size_t& module, std::string_view& task) -> kernel::Status {
    const auto slash = name.find('/');
    if (slash == std::string_view::npos || slash == 0 || slash + 1 == name.size())
      return kernel::Error{what + ": '" + std::string(name) + "' is not of the form module/task"};
    const std::string_view m = name.substr(0, slash);
    task = name.substr(slash + 1);
    for (module = 0; module < modules_.size(); ++module)
      if (modules_[module]->name() == m) return {};
    std::string known;
    for (const os::Node* node : modules_) known += (known.empty() ? "" : ", ") + node->name();
    return kernel::Error{what + ": no module '" + std::string(m) + "' (modules: " + known + ")"};
  };
  std::size_t sm = 0, rm = 0;
  std::string_view st, rt;
  if (auto s = split(sender, sm, st); !s) return kernel::Error{s.error()};
  if (auto s = split(receiver, rm, rt); !s) return kernel::Error{s.error()};
  return hook(sm, st, rm, rt, options);
}

kernel::Result<RemoteHookId> OrganismBus::hook(std::size_t sender_module, std::string_view sender,
                                               std::size_t receiver_module, std::string_view receiver,
                                               os::HookOptions options) {
  const auto name = [&](std::size_t m, std::string_view task) {
    return (m < modules_.size() ? modules_[m]->name() : "module " + std::to_string(m)) + "/" + std::string(task);
  };
  const std::string sender_name = name(sender_module, sender), receiver_name = name(receiver_module, receiver);
  const std::string what = "remote hook " + sender_name + " -> " + receiver_name;
  if (sender_module >= modules_.size() || receiver_module >= modules_.size())
    return kernel::Error{what + ": no such module (" + std::to_string(modules_.size()) + " modules)"};
  if (sender_module == receiver_module) return kernel::Error{what + ": both ends on one module; use a local hook"};
  os::Node& sn = *modules_[sender_module];
  os::Node& rn = *modules_[receiver_module];
  const auto s = sn.find(sender);
  if (!s) return kernel::Error{what + ": no task '" + std::string(sender) + "' on " + sn.name()};
  const auto r = rn.find(receiver);
  if (!r) return kernel::Error{what + ": no task '" + std::string(receiver) + "' on " + rn.name()};
  {
    // The rule of every hook (os::check_layouts) holds across the bus too: the two ends' declared
    // layouts must agree on the ports the hook carries, as Node::hook makes them agree locally.
    const auto s_info = sn.info(*s), r_info = rn.info(*r);
    const auto s_ports = sn.ports(*s), r_ports = rn.ports(*r);
    const os::PortDeclaration none;
    const os::PortDeclaration& sp = s_ports ? *s_ports : none;
    const os::PortDeclaration& rp = r_ports ? *r_ports : none;
    if (s_info && r_info) {
      const os::PortEnd from{sender_name, s_info->type, sp.inputs, sp.outputs};
      const os::PortEnd to{receiver_name, r_info->type, rp.inputs, rp.outputs};
      if (auto st = os::check_layouts(from, to, options.port); !st) return kernel::Error{what + ": " + st.error()};
    }
  }

  std::uint32_t id = 0;
  {
    std::lock_guard lock(mu_);
    for (const Remote& o : remotes_)
      if (o.sender == *s && o.receiver == *r && o.info.sender_module == sender_module &&
          o.info.receiver_module == receiver_module && os::same_hook_key(o.info.options.port, options.port))
        return kernel::Error{what + ": already hooked on that port (remote hook " + std::to_string(o.info.id.value) +
                             ")"};
    id = next_id_++;
  }
  // Task names allow letters, digits, '_', '.' and '-': "bus_to.m2.osc.1", or "bus_to.1" when
  // that would be too long.
  const auto proxy_name = [&](std::string_view way, std::size_t m, std::string_view task) {
    std::string n = std::string(way) + "." + modules_[m]->name() + "." + std::string(task) + "." + std::to_string(id);
    return n.size() <= 63 ? n : std::string(way) + "." + std::to_string(id);
  };
  const os::TaskOptions proxy_options{.priority = 0, .queue_capacity = options_.inbound_queue};
  auto outbound = sn.create(proxy_name("bus_to", receiver_module, receiver),
                            std::make_unique<io::OutboundProxy>(medium(), id), proxy_options);
  if (!outbound) return kernel::Error{what + ": " + outbound.error()};
  auto inbound = rn.create(proxy_name("bus_from", sender_module, sender),
                           std::make_unique<io::InboundProxy>(medium(), id), proxy_options);
  if (!inbound) {
    (void)sn.remove(*outbound);
    return kernel::Error{what + ": " + inbound.error()};
  }
  // At the receiver: the policy and the suppression window; at the sender: the port filter too.
  os::HookOptions in_options = options;
  in_options.port = -1;
  os::HookOptions out_options = options;
  out_options.suppress_window = kernel::Duration{0};
  auto in_hook = rn.hook(*inbound, *r, in_options);
  if (!in_hook) {
    (void)sn.remove(*outbound);
    (void)rn.remove(*inbound);
    return kernel::Error{what + ": " + in_hook.error()};
  }
  Remote remote;
  remote.info.id = RemoteHookId{id};
  remote.info.sender_module = sender_module;
  remote.info.receiver_module = receiver_module;
  remote.info.sender = sender_name;
  remote.info.receiver = receiver_name;
  remote.info.options = options;
  remote.sender = *s;
  remote.receiver = *r;
  remote.outbound = *outbound;
  remote.inbound = *inbound;
  remote.in_hook = *in_hook;
  {
    // Registered before the sender is hooked: under threads its first message may come at once.
    std::lock_guard lock(mu_);
    remote.info.state = label_[sender_module] == label_[receiver_module] ? LinkState::kUp : LinkState::kDown;
    remotes_.push_back(remote);
  }
  auto out_hook = sn.hook(*s, *outbound, out_options);
  if (!out_hook) {
    {
      std::lock_guard lock(mu_);
      std::erase_if(remotes_, [&](const Remote& o) { return o.info.id.value == id; });
    }
    (void)sn.remove(*outbound);
    (void)rn.remove(*inbound);
    return kernel::Error{what + ": " + out_hook.error()};
  }
  {
    std::lock_guard lock(mu_);
    if (Remote* reg = find_locked(id)) reg->out_hook = *out_hook;
  }
  sn.log().info("bus", what + ": remote hook " + std::to_string(id) + " made");
  return RemoteHookId{id};
}

kernel::Status OrganismBus::unhook(RemoteHookId id) {
  Remote gone;
  {
    std::lock_guard lock(mu_);
    Remote* r = find_locked(id.value);
    if (r == nullptr) return kernel::Error{"no remote hook " + std::to_string(id.value)};
    gone = *r;
    std::erase_if(remotes_, [&](const Remote& o) { return o.info.id == id; });
    // Its queued frames go; one on the wire finishes (a wire cannot be taken back) and is not
    // delivered.
    for (auto& queue : tx_) std::erase_if(queue, [&](const Frame& f) { return f.hook == id.value; });
    std::erase_if(propagating_, [&](const Frame& f) { return f.hook == id.value; });
  }
  (void)modules_[gone.info.sender_module]->remove(gone.outbound);
  (void)modules_[gone.info.receiver_module]->remove(gone.inbound);
  return {};
}

OrganismBus::Remote* OrganismBus::find_locked(std::uint32_t hook) {
  for (Remote& r : remotes_)
    if (r.info.id.value == hook) return &r;
  return nullptr;
}

RemoteHookInfo OrganismBus::fill(const Remote& r) const {
  RemoteHookInfo info = r.info;
  auto traffic = [](const os::Node& node, os::HookId id) {
    for (const os::HookInfo& h : node.hooks())
      if (h.id == id) return h.accounting;
    return os::HookTraffic{};
  };
  info.books = io::remote_hook_books(traffic(*modules_[r.info.sender_module], r.out_hook), info.medium,
                                     traffic(*modules_[r.info.receiver_module], r.in_hook));
  return info;
}

std::optional<RemoteHookInfo> OrganismBus::info(RemoteHookId id) const {
  Remote copy;
  {
    std::lock_guard lock(mu_);
    const auto it = std::find_if(remotes_.begin(), remotes_.end(), [&](const Remote& r) { return r.info.id == id; });
    if (it == remotes_.end()) return std::nullopt;
    copy = *it;
  }
  return fill(copy);
}

std::vector<RemoteHookInfo> OrganismBus::hooks() const {
  std::vector<Remote> copy;
  {
    std::lock_guard lock(mu_);
    copy = remotes_;
  }
  std::vector<RemoteHookInfo> out;
  out.reserve(copy.size());
  for (const Remote& r : copy) out.push_back(fill(r));
  return out;
}

std::string OrganismBus::listing() const {
  std::ostringstream out;
  out << "id  sender -> receiver  port  prio  state  attempted  delivered  dropped  in_flight\n";
  for (const RemoteHookInfo& h : hooks()) {
    out << h.id.value << "  " << h.sender << " -> " << h.receiver << "  "
        << (h.options.port < 0 ? std::string("any") : std::to_string(h.options.port)) << "  " << h.options.priority
        << "  " << to_string(h.state) << "  " << h.books.attempted << "  " << h.books.delivered << "  "
        << h.books.dropped() << "  " << h.books.in_flight;
    std::string causes;
    for (std::size_t c = 0; c < h.books.dropped_by.size(); ++c)
      if (h.books.dropped_by[c] > 0)
        causes += (causes.empty() ? "" : ", ") + std::string(io::to_string(static_cast<io::HookDrop>(c))) + " " +
                  std::to_string(h.books.dropped_by[c]);
    if (!causes.empty()) out << "  (" << causes << ")";
    out << '\n';
  }
  return out.str();
}

void OrganismBus::serve_shell(shell::Shell::Options& options) {
  options.remote_hook = [this](const std::string& sender, const std::string& receiver,
                               const os::HookOptions& hook_options) -> kernel::Result<std::string> {
    auto id = hook(sender, receiver, hook_options);
    if (!id) return kernel::Error{id.error()};
    return "remote hook " + std::to_string(id->value) + ": " + sender + " -> " + receiver + " (over the bus)";
  };
  options.remote_hooks = [this] { return listing(); };
}

// --- the medium --------------------------------------------------------------------------------

void OrganismBus::transmit(std::uint32_t hook, std::span<const std::byte> frame, std::size_t numbers) {
  std::lock_guard lock(mu_);
  const kernel::Time t = now();
  advance_locked(t);  // the wire may have come free before this frame arrived
  Remote* r = find_locked(hook);
  if (r == nullptr) return;  // unhooked while this message was in the outbound proxy
  ++r->info.medium.handed;
  const std::size_t from = r->info.sender_module, to = r->info.receiver_module;
  if (label_[from] != label_[to]) {
    ++r->info.medium.link_down;
    return;
  }
  auto& queue = tx_[from];
  if (queue.size() >= options_.tx_queue_frames) {
    // Full: a frame that would win arbitration against the worst queued one takes its place, so
    // a flood of low-priority frames cannot lock a higher-priority hook out of the queue.
    auto worst = queue.begin();
    for (auto it = queue.begin(); it != queue.end(); ++it)
      if (!beats(*it, *worst)) worst = it;
    Frame incoming;
    incoming.hook = hook;
    incoming.priority = r->info.options.priority;
    incoming.order = order_;
    if (!beats(incoming, *worst)) {
      ++r->info.medium.queue_full;
      return;
    }
    drop_locked(*worst, io::HookDrop::kQueueFull);
    queue.erase(worst);
  }
  Frame f;
  f.hook = hook;
  f.priority = r->info.options.priority;
  f.order = order_++;
  f.from = from;
  f.to = to;
  f.wire = wire_time(numbers);
  f.bits = 8 * frame.size();
  f.bytes = std::make_shared<const io::Bytes>(frame);
  tx_[from].push_back(std::move(f));
  ++r->info.medium.in_medium;
  start_next_locked(label_[from], t);
  arm_locked(t);
}

void OrganismBus::refuse(std::uint32_t hook, io::HookDrop cause) {
  std::lock_guard lock(mu_);
  Remote* r = find_locked(hook);
  if (r == nullptr) return;
  if (cause == io::HookDrop::kBlob) {
    ++r->info.medium.handed;
    ++r->info.medium.blob;
  } else if (cause == io::HookDrop::kDecode) {
    ++r->info.medium.decode;
  }
}

bool OrganismBus::beats(const Frame& a, const Frame& b) {
  if (a.priority != b.priority) return a.priority > b.priority;
  if (a.hook != b.hook) return a.hook < b.hook;
  return a.order < b.order;
}

bool OrganismBus::segment_busy_locked(std::size_t segment) const {
  return std::any_of(on_wire_.begin(), on_wire_.end(), [&](const Frame& f) { return label_[f.from] == segment; });
}

void OrganismBus::start_next_locked(std::size_t segment, kernel::Time at) {
  if (segment_busy_locked(segment)) return;
  std::deque<Frame>* best_queue = nullptr;
  std::size_t best = 0;
  for (std::size_t m = 0; m < tx_.size(); ++m) {
    if (label_[m] != segment) continue;
    for (std::size_t i = 0; i < tx_[m].size(); ++i) {
      const Frame& f = tx_[m][i];
      if (best_queue != nullptr && !beats(f, (*best_queue)[best])) continue;
      best_queue = &tx_[m];
      best = i;
    }
  }
  if (best_queue == nullptr) return;
  Frame f = std::move((*best_queue)[best]);
  best_queue->erase(best_queue->begin() + static_cast<std::ptrdiff_t>(best));
  f.done = at + f.wire;
  on_wire_.push_back(std::move(f));
}

void OrganismBus::advance_locked(kernel::Time now) {
  for (;;) {
    std::size_t wire = on_wire_.size();
    for (std::size_t i = 0; i < on_wire_.size(); ++i)
      if (wire == on_wire_.size() || on_wire_[i].done < on_wire_[wire].done) wire = i;
    const kernel::Time wire_end = wire < on_wire_.size() ? on_wire_[wire].done : kernel::kTimeNever;
    const kernel::Time arrival = propagating_.empty() ? kernel::kTimeNever : propagating_.front().done;
    if (std::min(wire_end, arrival) > now) break;
    if (wire_end <= arrival) {  // a wire comes free first: its next frame starts at that instant
      Frame f = std::move(on_wire_[wire]);
      on_wire_.erase(on_wire_.begin() + static_cast<std::ptrdiff_t>(wire));
      ++counts_.frames;
      counts_.bits += f.bits;
      counts_.busy += f.wire;
      const std::size_t segment = label_[f.from];
      f.done = wire_end + options_.latency;
      const auto at = std::upper_bound(propagating_.begin(), propagating_.end(), f.done,
                                       [](kernel::Time t, const Frame& o) { return t < o.done; });
      propagating_.insert(at, std::move(f));
      start_next_locked(segment, wire_end);
      continue;
    }
    Frame f = std::move(propagating_.front());
    propagating_.pop_front();
    Remote* r = find_locked(f.hook);
    if (r == nullptr) continue;  // unhooked meanwhile
    --r->info.medium.in_medium;
    os::Message m;
    m.time = f.done;
    m.payload = os::Payload(std::move(f.bytes));
    if (modules_[f.to]->post(r->inbound, m, os::QueuePolicy::kRefuse).ok())
      ++r->info.medium.posted;
    else
      ++r->info.medium.refused;
  }
  arm_locked(now);
}

void OrganismBus::arm_locked(kernel::Time now) {
  kernel::Time next = propagating_.empty() ? kernel::kTimeNever : propagating_.front().done;
  for (const Frame& f : on_wire_) next = std::min(next, f.done);
  if (next == armed_) return;
  armed_ = next;
  timer_->set_next(next == kernel::kTimeNever ? kernel::Duration{0} : std::max(next - now, kernel::Duration{1}));
}

void OrganismBus::on_timer() {
  std::lock_guard lock(mu_);
  armed_ = kernel::Time{-1};  // this tick used the armed instant up: arm again, whatever comes next
  advance_locked(now());
}

void OrganismBus::drop_locked(Frame& f, io::HookDrop cause) {
  Remote* r = find_locked(f.hook);
  if (r == nullptr) return;
  --r->info.medium.in_medium;
  if (cause == io::HookDrop::kLinkDown) ++r->info.medium.link_down;
  if (cause == io::HookDrop::kQueueFull) ++r->info.medium.queue_full;
}

void OrganismBus::set_labels_locked(std::vector<std::size_t> labels, kernel::Time now) {
  advance_locked(now);
  const auto apart = [&](const Frame& f) { return labels[f.from] != labels[f.to]; };
  for (auto& queue : tx_) {
    for (Frame& f : queue)
      if (apart(f)) drop_locked(f, io::HookDrop::kLinkDown);
    std::erase_if(queue, apart);
  }
  for (Frame& f : on_wire_)
    if (apart(f)) drop_locked(f, io::HookDrop::kLinkDown);
  std::erase_if(on_wire_, apart);
  for (Frame& f : propagating_)
    if (apart(f)) drop_locked(f, io::HookDrop::kLinkDown);
  std::erase_if(propagating_, apart);
  label_ = std::move(labels);
  for (Remote& r : remotes_) {
    const LinkState state =
        label_[r.info.sender_module] == label_[r.info.receiver_module] ? LinkState::kUp : LinkState::kDown;
    if (state == r.info.state) continue;
    r.info.state = state;
    const std::string text =
        "remote hook " + std::to_string(r.info.id.value) + " " + r.info.sender + " -> " + r.info.receiver +
        (state == LinkState::kDown ? ": link down, its messages are dropped until it is back" : ": link up");
    for (const std::size_t m : {r.info.sender_module, r.info.receiver_module}) {
      if (state == LinkState::kDown)
        modules_[m]->log().warn("bus", text);
      else
        modules_[m]->log().info("bus", text);
    }
    ++(state == LinkState::kDown ? counts_.links_down : counts_.links_up);
  }
  for (std::size_t m = 0; m < label_.size(); ++m)
    if (label_[m] == m) start_next_locked(m, now);
  arm_locked(now);
}

}  // namespace symb::sim::mujoco
