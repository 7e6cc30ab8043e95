// Probes: a task's internal state reaches the node's sink with the task's name, the channel, the
// node time and the values; nothing is delivered without a sink, and removing it stops delivery.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;

class Prober : public Task {
 public:
  int ticks = 0;
  bool saw_probing = false;

 protected:
  void on_tick() override {
    ++ticks;
    saw_probing = saw_probing || probing();
    probe("level", {static_cast<float>(ticks), 2.5f});
  }
};

struct Recorded {
  kernel::Time time;
  std::string node, task, channel;
  std::vector<float> values;
};

TEST(Probe, SamplesReachTheSinkWithNameChannelTimeAndValues) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto* prober = new Prober;
  ASSERT_TRUE(node.create("hormones", std::unique_ptr<Task>(prober), {.period = 10ms}));
  ex.run_for(25ms);  // ticks at 10 and 20 ms with nobody listening
  EXPECT_EQ(prober->ticks, 2);
  EXPECT_FALSE(prober->saw_probing);

  std::vector<Recorded> got;
  node.set_probe_sink([&](const ProbeSample& s) {
    got.push_back({s.time, std::string(s.node), std::string(s.task), std::string(s.channel),
                   std::vector<float>(s.values.begin(), s.values.end())});
  });
  EXPECT_TRUE(node.probing());
  ex.run_for(20ms);  // ticks at 30 and 40 ms
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].time, kernel::Time{30ms});
  EXPECT_EQ(got[0].node, "robot");
  EXPECT_EQ(got[0].task, "hormones");
  EXPECT_EQ(got[0].channel, "level");
  EXPECT_EQ(got[0].values, (std::vector<float>{3.0f, 2.5f}));
  EXPECT_EQ(got[1].values[0], 4.0f);
  EXPECT_TRUE(prober->saw_probing);

  node.set_probe_sink({});
  EXPECT_FALSE(node.probing());
  ex.run_for(20ms);
  EXPECT_EQ(got.size(), 2u);
  EXPECT_EQ(prober->ticks, 6);
}

}  // namespace
}  // namespace symb::os
