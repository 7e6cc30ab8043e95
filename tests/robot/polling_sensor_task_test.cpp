#include "symb/robot/polling_sensor_task.hpp"

#include <limits>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "fakes.hpp"
#include "support/eventually.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;
using testing::Collector;

// An ADC whose reading is scripted per poll: by default channel 0 reads the poll time in ms.
class FakeAdc final : public PollingSensor {
 public:
  FakeAdc() : PollingSensor("adc", {{"a0", "raw", 0, 1023}, {"a1", "raw", 0, 1023}}) {}
  std::function<kernel::Status(kernel::Time, std::span<float>)> script;
  std::vector<kernel::Time> polled_at;

  kernel::Status poll(kernel::Time now, std::span<float> out) override {
    polled_at.push_back(now);
    if (script) return script(now, out);
    out[0] = static_cast<float>(now / 1ms);
    out[1] = 1;
    return {};
  }
};

TEST(PollingSensorTask, PollsExactlyAtItsPeriod) {
  kernel::VirtualTimeExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  os::Node node(ex, {"bot"});
  auto t = std::make_unique<PollingSensorTask>(adc);
  PollingSensorTask* task = t.get();
  auto id = *node.create("adc_task", std::move(t), {.period = 30ms});
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(id, *node.create("c", std::move(c))));
  ex.run_for(100ms);
  const auto got = col->received();
  ASSERT_EQ(got.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const auto at = kernel::Time{30ms * static_cast<int>(i + 1)};
    EXPECT_EQ(got[i].time, at);
    EXPECT_EQ(adc->polled_at[i], at);
    EXPECT_EQ(got[i].values, (std::vector<float>{static_cast<float>(at / 1ms), 1}));
  }
  // A new period takes effect at once, counted from now.
  ASSERT_TRUE(node.set_period(id, 50ms));
  ex.run_for(100ms);  // to 200 ms: polls at 150 and 200
  EXPECT_EQ(adc->polled_at.back(), kernel::Time{200ms});
  EXPECT_EQ(task->stats().sent, 5u);
  EXPECT_EQ(task->stats().ticks, 5u);
}

TEST(PollingSensorTask, AFailedPollSendsNothingAndIsCountedAndLoggedAtALimitedRate) {
  kernel::VirtualTimeExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  adc->script = [](kernel::Time now, std::span<float> out) -> kernel::Status {
    if (now >= kernel::Time{60ms} && now < kernel::Time{3s}) return kernel::Error{"bus timeout"};
    out[0] = 1, out[1] = 2;
    return {};
  };
  os::Node node(ex, {"bot"});
  auto t = std::make_unique<PollingSensorTask>(adc);
  PollingSensorTask* task = t.get();
  auto id = *node.create("adc_task", std::move(t), {.period = 30ms});
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(id, *node.create("c", std::move(c))));
  ex.run_for(3030ms);
  const auto got = col->received();
  ASSERT_EQ(got.size(), 3u);  // 30 ms, then nothing until 3000 ms and 3030 ms
  EXPECT_EQ(got[0].time, kernel::Time{30ms});
  EXPECT_EQ(got[1].time, kernel::Time{3000ms});
  const PollingStats s = task->stats();
  EXPECT_EQ(s.ticks, 101u);
  EXPECT_EQ(s.failed, 98u);  // 60 ms .. 2970 ms
  EXPECT_EQ(s.sent, 3u);
  EXPECT_EQ(s.consecutive_failures, 0u);
  // Warnings at 60 ms, 1080 ms and 2100 ms (one per second at most), each with its count.
  std::vector<os::LogEntry> warns;
  for (const auto& e : node.log().since(0))
    if (e.level == os::LogLevel::kWarn) warns.push_back(e);
  ASSERT_EQ(warns.size(), 3u);
  EXPECT_EQ(warns[0].time, kernel::Time{60ms});
  EXPECT_EQ(warns[0].text, "1 failed poll(s) of 'adc', latest: bus timeout (nothing sent)");
  EXPECT_EQ(warns[1].time, kernel::Time{1080ms});
  EXPECT_EQ(warns[1].text.substr(0, 18), "34 failed poll(s) ");
  EXPECT_EQ(warns[2].time, kernel::Time{2100ms});
}

TEST(PollingSensorTask, NaNAndUnwrittenChannelsAreRejectedAndRangesClamped) {
  kernel::VirtualTimeExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  int n = 0;
  adc->script = [&](kernel::Time, std::span<float> out) -> kernel::Status {
    switch (n++) {
      case 0: out[0] = std::numeric_limits<float>::quiet_NaN(), out[1] = 1; break;
      case 1: out[0] = 5; break;  // "succeeds" without writing a1
      case 2: out[0] = -3, out[1] = 4000; break;
      default: out[0] = 1, out[1] = 1; break;
    }
    return {};
  };
  os::Node node(ex, {"bot"});
  auto t = std::make_unique<PollingSensorTask>(adc);
  PollingSensorTask* task = t.get();
  auto id = *node.create("adc_task", std::move(t), {.period = 10ms});
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(id, *node.create("c", std::move(c))));
  ex.run_for(40ms);
  const auto got = col->received();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].time, kernel::Time{30ms});
  EXPECT_EQ(got[0].values, (std::vector<float>{0, 1023}));
  const PollingStats s = task->stats();
  EXPECT_EQ(s.rejected, 2u);
  EXPECT_EQ(s.clamped_values, 2u);
  EXPECT_EQ(s.sent, 2u);
  bool named = false;
  for (const auto& e : node.log().since(0))
    if (e.text.find("NaN in channel 'a0'") != std::string::npos) named = true;
  EXPECT_TRUE(named);
}

TEST(PollingSensorTask, AClosedDeviceIsAFailedPollNotAReopen) {
  kernel::VirtualTimeExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  os::Node node(ex, {"bot"});
  auto t = std::make_unique<PollingSensorTask>(adc);
  PollingSensorTask* task = t.get();
  (void)*node.create("adc_task", std::move(t), {.period = 10ms});
  ex.run_for(10ms);
  EXPECT_TRUE(adc->is_open());
  adc->close();
  ex.run_for(20ms);
  EXPECT_FALSE(adc->is_open());
  EXPECT_EQ(task->stats().failed, 2u);
  EXPECT_EQ(task->stats().consecutive_failures, 2u);
  EXPECT_EQ(adc->polled_at.size(), 1u);
}

TEST(PollingSensorTask, ADriverThatThrowsIsAFailedPollNotAFault) {
  kernel::VirtualTimeExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  adc->script = [](kernel::Time, std::span<float>) -> kernel::Status { throw std::runtime_error("oops"); };
  os::Node node(ex, {"bot"});
  auto t = std::make_unique<PollingSensorTask>(adc);
  PollingSensorTask* task = t.get();
  auto id = *node.create("adc_task", std::move(t), {.period = 10ms});
  ex.run_for(30ms);
  EXPECT_EQ(task->stats().failed, 3u);
  EXPECT_EQ(node.info(id)->state, os::TaskState::kRunning);
}

TEST(PollingSensorTask, RunsUnderThreads) {
  kernel::ThreadExecutor ex;
  auto adc = std::make_shared<FakeAdc>();
  os::Node node(ex, {"bot"});
  auto id = *node.create("adc_task", std::make_unique<PollingSensorTask>(adc), {.period = 5ms});
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(id, *node.create("c", std::move(c))));
  EXPECT_TRUE(symb::testing::eventually([&] { return col->count() >= 5; }));
  ASSERT_TRUE(node.remove(id));
  node.wait_released();
  const auto got = col->received();
  for (std::size_t i = 1; i < got.size(); ++i) EXPECT_GT(got[i].time, got[i - 1].time);
}

}  // namespace
}  // namespace symb::robot
