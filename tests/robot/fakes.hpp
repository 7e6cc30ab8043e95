// Fakes shared by the robot tests: drivers that record what they were told, a collector task,
// and a plant task that plays the robot's body (integrates wheel speeds, sends odometry).
#pragma once

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/task.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/differential_drive.hpp"
#include "symb/robot/drive_goal.hpp"
#include "symb/robot/polling_sensor_task.hpp"
#include "symb/robot/ports.hpp"

namespace symb::robot::testing {

using namespace std::chrono_literals;

struct Received {
  kernel::Time time;
  os::Port port;
  std::vector<float> values;
};

// Records every message it receives.
class Collector : public os::Task {
 public:
  std::vector<Received> received() const {
    std::lock_guard lock(mu_);
    return received_;
  }
  std::size_t count() const { return count_.load(); }
  // The goal statuses among the messages, in order.
  std::vector<GoalStatus> statuses() const {
    std::vector<GoalStatus> out;
    for (const auto& r : received())
      if (r.port == kStatusPort)
        if (auto s = decode_status(r.values)) out.push_back(*s);
    return out;
  }

 protected:
  void on_message(const os::Message& m) override {
    {
      std::lock_guard lock(mu_);
      received_.push_back({m.time, m.port, {m.numbers().begin(), m.numbers().end()}});
    }
    count_.fetch_add(1);
  }

 private:
  mutable std::mutex mu_;
  std::vector<Received> received_;
  std::atomic<std::size_t> count_{0};
};

// A drive that remembers every command.
class FakeDrive final : public DifferentialDrive {
 public:
  explicit FakeDrive(double max_speed = 0.5) : DifferentialDrive("wheels", max_speed) {}
  std::vector<std::pair<double, double>> commands() const {
    std::lock_guard lock(mu_);
    return commands_;
  }
  std::atomic<bool> fail{false};
  // Called with each command the drive takes, before it is stored (set before the drive is used).
  std::function<void(double, double)> on_command;

 protected:
  kernel::Status apply_wheel_speeds(double left, double right) override {
    if (fail) return kernel::Error{"motor controller not answering"};
    if (on_command) on_command(left, right);
    std::lock_guard lock(mu_);
    commands_.emplace_back(left, right);
    return {};
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::pair<double, double>> commands_;
};

// The robot's body: every tick, integrates the drive's wheel speeds (exactly: a circle arc per
// step) and sends odometry on kDataPort, either as a pose [x, y, theta] (theta wrapped to
// (-pi, pi], as real pose sources do) or as cumulative wheel distances [left, right].
class Plant : public os::Task {
 public:
  Plant(std::shared_ptr<FakeDrive> drive, double wheel_base, bool wheel_distances = false)
      : drive_(std::move(drive)), wheel_base_(wheel_base), wheel_distances_(wheel_distances) {}
  double x() const { return x_.load(); }
  double y() const { return y_.load(); }
  double theta() const { return theta_.load(); }  // unwrapped

 protected:
  void on_start() override {
    last_ = now();
    publish();
  }
  void on_tick() override {
    const double dt = kernel::to_seconds(now() - last_);
    last_ = now();
    auto [l, r] = drive_->wheel_speeds();
    const double v = (l + r) / 2, w = (r - l) / wheel_base_;
    double x = x_.load(), y = y_.load(), th = theta_.load();
    if (std::abs(w) < 1e-12) {
      x += v * std::cos(th) * dt;
      y += v * std::sin(th) * dt;
    } else {
      x += v / w * (std::sin(th + w * dt) - std::sin(th));
      y -= v / w * (std::cos(th + w * dt) - std::cos(th));
    }
    th += w * dt;
    x_ = x, y_ = y, theta_ = th;
    left_ += l * dt;
    right_ += r * dt;
    publish();
  }

 private:
  void publish() {
    if (wheel_distances_) {
      send(kDataPort, {static_cast<float>(left_), static_cast<float>(right_)});
    } else {
      const double wrapped = std::remainder(theta_.load(), 2 * 3.14159265358979323846);
      send(kDataPort, {static_cast<float>(x_.load()), static_cast<float>(y_.load()), static_cast<float>(wrapped)});
    }
  }

  std::shared_ptr<FakeDrive> drive_;
  double wheel_base_;
  bool wheel_distances_;
  kernel::Time last_{0};
  std::atomic<double> x_{0}, y_{0}, theta_{0};
  double left_ = 0, right_ = 0;
};

// Drives a virtual-time run until `done` or a real-time deadline, for data that comes from
// threads outside the executor.
template <class F>
bool pump(kernel::VirtualTimeExecutor& ex, F done, std::chrono::milliseconds step = 1ms) {
  const auto end = std::chrono::steady_clock::now() + 20s;
  while (!done() && std::chrono::steady_clock::now() < end) {
    ex.wait_injected(2ms);
    ex.run_for(step);
  }
  return done();
}

}  // namespace symb::robot::testing
