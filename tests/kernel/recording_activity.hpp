// RecordingActivity: an Activity that writes every call it gets into a log as "name:what@ms", the
// instant read from its executor's clock, so the executor tests can check exact orders and
// instants whatever executor they drive.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "symb/kernel/executor.hpp"

namespace symb::kernel::test_support {

struct RecordingActivity final : Activity {
  RecordingActivity(std::string n, const Executor& e, std::vector<std::string>& l)
      : name(std::move(n)), exec(e), log(l) {}
  void on_activity_attached(ActivitySlot& s) override { slot = &s; }
  void on_activity_start() override { note("start"); }
  void on_activity_input() override {
    note("input");
    if (on_input) on_input();
  }
  void on_activity_tick() override {
    note("tick");
    if (on_tick) on_tick();
  }
  void on_activity_stop() override { note("stop"); }
  void on_activity_released() override { note("released"); }
  void note(const char* what) {
    log.push_back(name + ":" + what + "@" + std::to_string(exec.clock().now().count() / 1000000));
  }

  std::string name;
  const Executor& exec;
  std::vector<std::string>& log;
  ActivitySlot* slot = nullptr;
  std::function<void()> on_input, on_tick;
};

}  // namespace symb::kernel::test_support
