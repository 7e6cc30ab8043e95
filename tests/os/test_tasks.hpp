// Small tasks shared by the os tests: one that records what it receives, one that emits on tick,
// and one that throws on demand.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "symb/os/node.hpp"
#include "symb/os/task.hpp"

namespace symb::os::testing {

struct Received {
  kernel::Time time;
  TaskId source;
  Port port;
  std::vector<float> values;
};

class Collector : public Task {
 public:
  std::vector<Received> received() const {
    std::lock_guard lock(mu_);
    return received_;
  }
  std::size_t count() const { return count_.load(); }
  std::function<void(const Message&)> on_each;

 protected:
  void on_message(const Message& m) override {
    {
      std::lock_guard lock(mu_);
      received_.push_back({m.time, m.source, m.port, {m.numbers().begin(), m.numbers().end()}});
    }
    count_.fetch_add(1);
    if (on_each) on_each(m);
  }

 private:
  mutable std::mutex mu_;
  std::vector<Received> received_;
  std::atomic<std::size_t> count_{0};
};

// Sends {n} on port `port` every tick, n counting up from 1.
class Emitter : public Task {
 public:
  explicit Emitter(Port port = 0) : port_(port) {}
  int emitted() const { return n_.load(); }

 protected:
  void on_tick() override { send(port_, {static_cast<float>(n_.fetch_add(1) + 1)}); }

 private:
  Port port_;
  std::atomic<int> n_{0};
};

// Runs a caller-supplied function for each handler; handy for one-off behaviours.
class Scripted : public Task {
 public:
  std::function<void(Scripted&)> start, tick, stop;
  std::function<void(Scripted&, const Message&)> message;
  using Task::id;
  using Task::node;
  using Task::now;
  using Task::random;
  using Task::send;

 protected:
  void on_start() override {
    if (start) start(*this);
  }
  void on_tick() override {
    if (tick) tick(*this);
  }
  void on_message(const Message& m) override {
    if (message) message(*this, m);
  }
  void on_stop() override {
    if (stop) stop(*this);
  }
};

}  // namespace symb::os::testing
