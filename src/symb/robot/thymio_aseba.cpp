#include "symb/robot/thymio_aseba.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "symb/io/reopen_backoff.hpp"
#include "symb/robot/thymio_ir.hpp"

namespace symb::robot::thymio {

namespace {

std::vector<ChannelSpec> ir_channels() {
  std::vector<ChannelSpec> c;
  for (std::size_t i = 0; i < kIrCount; ++i)
    c.push_back(ChannelSpec{"ir" + std::to_string(i), "raw", 0.0f, static_cast<float>(kIrMax)});
  return c;
}

std::vector<ChannelSpec> ground_channels() {
  return {ChannelSpec{"left", "reflectance", 0.0f, 1.0f}, ChannelSpec{"right", "reflectance", 0.0f, 1.0f}};
}

std::vector<ChannelSpec> wheel_channels() {
  return {ChannelSpec{"left", "thymio", -500.0f, 500.0f}, ChannelSpec{"right", "thymio", -500.0f, 500.0f}};
}

// The wheels device: a command goes to the robot at once, on the caller's thread.
class AsebaWheels final : public Actuator {
 public:
  AsebaWheels() : Actuator("wheels", wheel_channels()) {}
  void bind(std::weak_ptr<AsebaThymio> owner) { owner_ = std::move(owner); }

 protected:
  kernel::Status apply(std::span<const float> values) override {
    auto owner = owner_.lock();
    if (!owner) return kernel::Error{"the Thymio is gone"};
    return owner->write_wheels(values[0], values[1]);
  }

 private:
  std::weak_ptr<AsebaThymio> owner_;
};

std::int16_t to_target(float units, double scale) {
  const double v = std::clamp(std::round(static_cast<double>(units) * scale), -32768.0, 32767.0);
  return static_cast<std::int16_t>(v);
}

}  // namespace

kernel::Result<AsebaLayout> thymio_layout(const io::aseba::NodeDescription& d) {
  std::string wrong;
  auto need = [&](std::string_view name, std::uint16_t size) -> std::uint16_t {
    const io::aseba::NamedVariable* v = d.find(name);
    if (v == nullptr) {
      wrong += std::string(wrong.empty() ? "" : ", ") + "no " + std::string(name) + " (" + std::to_string(size) +
               (size == 1 ? " word)" : " words)");
      return 0;
    }
    if (v->size != size) {
      wrong += std::string(wrong.empty() ? "" : ", ") + std::string(name) + " has " + std::to_string(v->size) +
               " words, not " + std::to_string(size);
      return 0;
    }
    return v->address;
  };
  AsebaLayout l;
  l.prox_horizontal = need("prox.horizontal", kIrCount);
  l.motor_left_target = need("motor.left.target", 1);
  l.motor_right_target = need("motor.right.target", 1);
  if (!wrong.empty())
    return kernel::Error{"node " + std::to_string(d.node) + " '" + d.name + "' is not a Thymio II: " + wrong};
  if (const auto* g = d.find("prox.ground.reflected"); g != nullptr && g->size == 2)
    l.prox_ground_reflected = g->address;
  const auto* ls = d.find("motor.left.speed");
  const auto* rs = d.find("motor.right.speed");
  if (ls != nullptr && rs != nullptr && ls->size == 1 && rs->size == 1) {
    l.motor_left_speed = ls->address;
    l.motor_right_speed = rs->address;
  }
  return l;
}

std::shared_ptr<AsebaThymio> AsebaThymio::create(std::shared_ptr<io::IOStream> stream, AsebaThymioOptions options) {
  if (!stream) throw std::invalid_argument("AsebaThymio: no stream");
  if (options.control_period.count() <= 0 || options.reply_timeout.count() <= 0 || options.lost_periods < 1)
    throw std::invalid_argument("AsebaThymio: control period, reply timeout and lost_periods must be positive");
  if (!(std::isfinite(options.speed_scale) && options.speed_scale > 0 && options.speed_scale <= 1))
    throw std::invalid_argument("AsebaThymio: speed_scale must be in (0, 1]");
  std::shared_ptr<AsebaThymio> t(new AsebaThymio(std::move(stream), options));
  std::static_pointer_cast<AsebaWheels>(t->wheels_)->bind(t);
  return t;
}

AsebaThymio::AsebaThymio(std::shared_ptr<io::IOStream> stream, AsebaThymioOptions options)
    : options_(options),
      link_(std::move(stream)),
      ir_(std::make_shared<Sensor>("ir", ir_channels())),
      ground_(std::make_shared<Sensor>("ground", ground_channels())),
      wheels_(std::make_shared<AsebaWheels>()),
      backoff_(options.reopen_first, options.reopen_most) {}

AsebaThymio::~AsebaThymio() { stop(); }

void AsebaThymio::on_report(Reporter r) {
  std::lock_guard lock(mu_);
  reporter_ = std::move(r);
}

void AsebaThymio::report(os::LogLevel level, const std::string& text) {
  Reporter r;
  {
    std::lock_guard lock(mu_);
    r = reporter_;
  }
  if (r) r(level, text);
}

kernel::Time AsebaThymio::now() const {
  return std::chrono::duration_cast<kernel::Duration>(std::chrono::steady_clock::now().time_since_epoch());
}

kernel::Status AsebaThymio::connect() {
  if (!link_.stream().is_open())
    if (auto st = link_.stream().open(); !st) return st;
  link_.reset();
  return handshake();
}

kernel::Status AsebaThymio::handshake() {
  auto node = link_.discover(options_.connect_timeout);
  if (!node) return kernel::Error{node.error()};
  auto d = link_.describe(*node, options_.connect_timeout);
  if (!d) return kernel::Error{d.error()};
  auto checked = thymio_layout(*d);
  if (!checked) return kernel::Error{checked.error()};
  AsebaLayout layout = *checked;
  // One read per period: prox.horizontal, the ground sensors and the measured speeds together
  // when they lie close (as on a Thymio: 42..60); what lies far is not read.
  std::uint32_t lo = layout.prox_horizontal, hi = lo + kIrCount;
  if (layout.prox_ground_reflected) {
    const std::uint32_t g = *layout.prox_ground_reflected;
    if (std::max(hi, g + 2) - std::min(lo, g) <= 64) {
      lo = std::min(lo, g);
      hi = std::max(hi, g + 2);
    } else {
      layout.prox_ground_reflected.reset();
    }
  }
  if (layout.motor_left_speed) {
    const std::uint32_t l2 = std::min(*layout.motor_left_speed, *layout.motor_right_speed);
    const std::uint32_t h2 = std::max(*layout.motor_left_speed, *layout.motor_right_speed) + 1u;
    if (std::max(hi, h2) - std::min(lo, l2) <= 64) {
      lo = std::min(lo, l2);
      hi = std::max(hi, h2);
    } else {
      layout.motor_left_speed.reset();
      layout.motor_right_speed.reset();
    }
  }
  {
    std::lock_guard lock(mu_);
    node_ = *d;
    layout_ = layout;
    block_start_ = static_cast<std::uint16_t>(lo);
    block_count_ = static_cast<std::uint16_t>(hi - lo);
    stats_.node = *node;
    stats_.node_name = d->name;
    stats_.up = true;
  }
  misses_ = 0;
  last_read_.reset();
  // Whatever it was told before (by us before a loss, or by anyone), it starts standing still.
  if (auto st = write_targets(0, 0); !st) {
    std::lock_guard lock(mu_);
    stats_.up = false;
    return st;
  }
  std::lock_guard lock(mu_);
  ++stats_.stops;
  return {};
}

kernel::Status AsebaThymio::write_targets(std::int16_t left, std::int16_t right) {
  std::lock_guard write(write_mu_);
  return write_targets_locked(left, right);
}

kernel::Status AsebaThymio::write_targets_locked(std::int16_t left, std::int16_t right) {
  io::aseba::NodeDescription node;
  AsebaLayout layout;
  {
    std::lock_guard lock(mu_);
    if (!node_) return kernel::Error{"no Thymio connected"};
    node = *node_;
    layout = layout_;
  }
  kernel::Status st;
  if (layout.motor_right_target == layout.motor_left_target + 1) {
    const std::int16_t both[2] = {left, right};
    st = link_.set(node, layout.motor_left_target, both);
  } else {
    st = link_.set(node, layout.motor_left_target, std::span<const std::int16_t>(&left, 1));
    if (st) st = link_.set(node, layout.motor_right_target, std::span<const std::int16_t>(&right, 1));
  }
  if (st) {
    std::lock_guard lock(mu_);
    stats_.left_target = left;
    stats_.right_target = right;
  }
  return st;
}

kernel::Status AsebaThymio::write_wheels(float left, float right) {
  std::lock_guard write(write_mu_);
  {
    std::lock_guard lock(mu_);
    if (!stats_.up || stopping_) {
      ++stats_.wheel_refused;
      return kernel::Error{stopping_ ? "the Thymio's driver is stopped" : "the link to the Thymio is down"};
    }
  }
  auto st = write_targets_locked(to_target(left, options_.speed_scale), to_target(right, options_.speed_scale));
  std::lock_guard lock(mu_);
  ++(st ? stats_.wheel_writes : stats_.wheel_refused);
  return st;
}

void AsebaThymio::start() {
  std::lock_guard lock(mu_);
  if (thread_.joinable()) return;
  stopping_ = false;
  thread_ = std::thread([this] { run(); });
}

void AsebaThymio::stop() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  bool up = false;
  {
    std::lock_guard lock(mu_);
    up = stats_.up;
  }
  if (up && write_targets(0, 0)) {
    std::lock_guard lock(mu_);
    ++stats_.stops;
  }
}

void AsebaThymio::run() {
  for (;;) {
    const auto t0 = std::chrono::steady_clock::now();
    bool up = false;
    {
      std::lock_guard lock(mu_);
      if (stopping_) return;
      up = stats_.up;
    }
    if (up)
      read_once();
    else
      try_reconnect();
    std::unique_lock lock(mu_);
    cv_.wait_until(lock, t0 + options_.control_period, [&] { return stopping_; });
  }
}

void AsebaThymio::read_once() {
  // The sample's time is when it was asked for: the robot read its sensors after that.
  const kernel::Time t = now();
  auto v = link_.get(*node_, block_start_, block_count_, options_.reply_timeout);
  if (!v) {
    if (!link_.stream().is_open()) return lose(v.error());
    {
      std::lock_guard lock(mu_);
      ++stats_.missed_reads;
      stats_.link = link_.stats();
    }
    if (++misses_ >= options_.lost_periods)
      lose("no answer to " + std::to_string(misses_) + " reads in a row (" + v.error() + ")");
    return;
  }
  misses_ = 0;
  const kernel::Duration round_trip = now() - t;
  float ir[kIrCount];
  for (std::size_t i = 0; i < kIrCount; ++i)
    ir[i] = static_cast<float>((*v)[layout_.prox_horizontal - block_start_ + i]);
  ir_->publish(std::span<const float>(ir, kIrCount), t);
  if (layout_.prox_ground_reflected) {
    const std::size_t g = *layout_.prox_ground_reflected - block_start_;
    const float ground[2] = {static_cast<float>((*v)[g] / kGroundFullScale),
                             static_cast<float>((*v)[g + 1] / kGroundFullScale)};
    ground_->publish(std::span<const float>(ground, 2), t);
  }
  std::lock_guard lock(mu_);
  stats_.last_round_trip = round_trip;
  ++stats_.samples;
  stats_.link = link_.stats();
  if (layout_.motor_left_speed && last_read_) {
    // Measured speeds held over the interval since the last read (at most three periods, so a
    // gap in the readings is not integrated as motion).
    const double dt = std::min(kernel::to_seconds(t - *last_read_), 3 * kernel::to_seconds(options_.control_period));
    const double vl = (*v)[*layout_.motor_left_speed - block_start_] * options_.cm_per_unit;
    const double vr = (*v)[*layout_.motor_right_speed - block_start_] * options_.cm_per_unit;
    const double speed = (vl + vr) / 2, turn = (vr - vl) / kWheelBase;
    stats_.x += speed * std::cos(stats_.heading) * dt;
    stats_.y += speed * std::sin(stats_.heading) * dt;
    stats_.heading = std::remainder(stats_.heading + turn * dt, 2 * std::numbers::pi);
    stats_.path += std::abs(speed) * dt;
  }
  last_read_ = t;
}

void AsebaThymio::lose(const std::string& why) {
  const kernel::Time noticed = now();
  std::uint16_t node = 0;
  {
    std::lock_guard lock(mu_);
    if (!stats_.up) return;
    stats_.up = false;
    node = stats_.node;
  }
  // Stop first, report after: the stop must not wait for whoever reads the report.
  std::string stop_note = "zero targets written";
  if (!link_.stream().is_open()) {
    stop_note = "the robot cannot be reached: it keeps its last target until the link returns";
  } else if (auto st = write_targets(0, 0); !st) {
    stop_note = "zero targets not written (" + st.error() + ")";
  }
  {
    std::lock_guard lock(mu_);
    // Counted once the stop is done: whoever sees the loss sees the wheels' targets it left.
    ++stats_.losses;
    ++stats_.stops;
    stats_.left_target = stats_.right_target = 0;
    stats_.last_stop_delay = now() - noticed;
    stats_.link = link_.stats();
  }
  link_.stream().close();
  backoff_.lost(now());
  report(os::LogLevel::kWarn,
         "aseba link to node " + std::to_string(node) + " lost: " + why + "; wheels stopped (" + stop_note +
             "); reconnecting at once, then after " + std::to_string(kernel::to_milliseconds(options_.reopen_first)) +
             " ms doubling up to " + std::to_string(kernel::to_milliseconds(options_.reopen_most)) + " ms");
}

void AsebaThymio::try_reconnect() {
  const kernel::Time t = now();
  if (!backoff_.down()) backoff_.lost(t);  // started without a connect() that succeeded
  if (!backoff_.due(t)) return;
  kernel::Status st = link_.stream().open();
  if (st) {
    link_.reset();
    st = handshake();
  }
  if (!st) {
    link_.stream().close();
    const kernel::Duration wait = backoff_.failed(now());
    if (backoff_.attempts() <= 3 || backoff_.attempts() % 10 == 0)
      report(os::LogLevel::kInfo, "aseba reconnect attempt " + std::to_string(backoff_.attempts()) +
                                      " failed: " + st.error() + "; next in " +
                                      std::to_string(kernel::to_milliseconds(wait)) + " ms");
    return;
  }
  const kernel::Duration outage = backoff_.reopened(now());
  std::string name;
  {
    std::lock_guard lock(mu_);
    ++stats_.reconnects;
    name = stats_.node_name;
  }
  report(os::LogLevel::kInfo, "aseba link back after " + std::to_string(kernel::to_milliseconds(outage)) +
                                  " ms: node " + std::to_string(stats().node) + " '" + name +
                                  "', wheels stopped until the controller commands them");
}

AsebaThymioStats AsebaThymio::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

}  // namespace symb::robot::thymio
