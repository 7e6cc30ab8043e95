#include "symb/robot/sensor.hpp"

#include <limits>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/depth_image.hpp"

#include "fakes.hpp"
#include "support/eventually.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;
using testing::Collector;

std::vector<ChannelSpec> ir_channels() { return {{"ir0", "raw", 0, 1023}, {"ir1", "raw", 0, 1023}}; }

std::size_t sensor_warnings_containing(os::Node& node, std::string_view text) {
  std::size_t n = 0;
  for (const auto& e : node.log().since(0))
    if (e.level == os::LogLevel::kWarn && e.text.find(text) != std::string::npos) ++n;
  return n;
}

struct SensorRig {
  explicit SensorRig(kernel::Executor& ex, Sensor::Options o = {}) : node(ex, {"bot"}) {
    sensor = std::make_shared<Sensor>("ir", ir_channels(), o);
    task = *node.create("ir_task", std::make_unique<SensorTask>(sensor));
    auto c = std::make_unique<Collector>();
    col = c.get();
    // Room for every sample: this checks the sensor's path, not the hook's keep-newest policy.
    sink = *node.create("controller", std::move(c), {.queue_capacity = 1024});
    EXPECT_TRUE(node.hook(task, sink));
  }
  os::Node node;
  std::shared_ptr<Sensor> sensor;
  os::TaskId task, sink;
  Collector* col = nullptr;
};

TEST(Sensor, PushesFromAnotherThreadReachHookedTasksUnderVirtualTime) {
  kernel::VirtualTimeExecutor ex;
  SensorRig rig(ex, {.mailbox = 256});
  ex.run_for(1ms);
  ASSERT_TRUE(rig.sensor->has_listener());
  ASSERT_TRUE(rig.sensor->is_open());  // the task opened it
  std::thread driver([&] {
    for (int i = 0; i < 100; ++i) {
      const float v[2] = {static_cast<float>(i), 5000.0f};  // the second channel saturates
      EXPECT_EQ(rig.sensor->publish(v, kernel::Time{i}), PublishResult::kQueued);
      if (i % 10 == 0) std::this_thread::sleep_for(100us);
    }
  });
  EXPECT_TRUE(testing::pump(ex, [&] { return rig.col->count() == 100; }));
  driver.join();
  const auto got = rig.col->received();
  ASSERT_EQ(got.size(), 100u);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(got[static_cast<std::size_t>(i)].values, (std::vector<float>{static_cast<float>(i), 1023.0f}));
    EXPECT_EQ(got[static_cast<std::size_t>(i)].port, kDataPort);
  }
  const SensorStats s = rig.sensor->stats();
  EXPECT_EQ(s.published, 100u);
  EXPECT_EQ(s.queued_total, 100u);
  EXPECT_EQ(s.taken, 100u);
  EXPECT_EQ(s.overwritten, 0u);
  EXPECT_EQ(s.clamped_values, 100u);
  // Clamping is logged, at a limited rate: not once per sample.
  const std::size_t warns = sensor_warnings_containing(rig.node, "clamped");
  EXPECT_GE(warns, 1u);
  EXPECT_LT(warns, 5u);
}

TEST(Sensor, SamplesAreForwardedAtTheVirtualInstantTheExecutorTakesThem) {
  kernel::VirtualTimeExecutor ex;
  SensorRig rig(ex);
  ex.run_for(5ms);
  std::thread driver([&] {
    for (int i = 0; i < 3; ++i) {
      const float v[2] = {static_cast<float>(i), 1.0f};
      (void)rig.sensor->publish(v, kernel::Time{i});
    }
  });
  driver.join();
  ex.run_for(0ms);  // the notification runs at 5 ms, and the task with it
  const auto got = rig.col->received();
  ASSERT_EQ(got.size(), 3u);
  for (const auto& r : got) EXPECT_EQ(r.time, kernel::Time{5ms});
  EXPECT_EQ(rig.sensor->latest()->time, kernel::Time{2});
}

// The task takes its mailbox a few samples at a time (into a buffer on its stack): a mailbox
// holding several rounds' worth is forwarded whole, in order, in one wake.
TEST(Sensor, AMailboxOfManyRoundsIsForwardedWholeAndInOrder) {
  kernel::VirtualTimeExecutor ex;
  SensorRig rig(ex, {.mailbox = 64});
  ex.run_for(1ms);
  for (const int n : {3, 4, 5, 8, 9, 41}) {
    const std::size_t before = rig.col->count();
    std::thread driver([&] {
      for (int i = 0; i < n; ++i) {
        const float v[2] = {static_cast<float>(i), 2.0f};
        (void)rig.sensor->publish(v, kernel::Time{i});
      }
    });
    driver.join();
    ex.run_for(0ms);
    const auto got = rig.col->received();
    ASSERT_EQ(got.size(), before + static_cast<std::size_t>(n)) << n << " samples";
    for (int i = 0; i < n; ++i)
      EXPECT_EQ(got[before + static_cast<std::size_t>(i)].values, (std::vector<float>{static_cast<float>(i), 2.0f}));
  }
  const SensorStats s = rig.sensor->stats();
  EXPECT_EQ(s.taken, 70u);
  EXPECT_EQ(s.overwritten, 0u);
}

TEST(Sensor, PushesFromAnotherThreadReachHookedTasksUnderThreads) {
  kernel::ThreadExecutor ex;
  SensorRig rig(ex, {.mailbox = 256});
  ASSERT_TRUE(symb::testing::eventually([&] { return rig.sensor->has_listener(); }));
  std::thread driver([&] {
    for (int i = 0; i < 200; ++i) {
      const float v[2] = {static_cast<float>(i), -1.0f};
      (void)rig.sensor->publish(v, kernel::Time{i});
      if (i % 20 == 0) std::this_thread::sleep_for(200us);
    }
  });
  driver.join();
  EXPECT_TRUE(symb::testing::eventually([&] { return rig.col->count() == 200; }));
  const auto got = rig.col->received();
  ASSERT_EQ(got.size(), 200u);
  for (int i = 0; i < 200; ++i)
    EXPECT_EQ(got[static_cast<std::size_t>(i)].values, (std::vector<float>{static_cast<float>(i), 0.0f}));
  const SensorStats s = rig.sensor->stats();
  EXPECT_EQ(s.taken + s.overwritten, s.queued_total);
  EXPECT_EQ(s.overwritten, 0u);
}

TEST(Sensor, AFullMailboxKeepsTheNewestAndEveryCounterAddsUp) {
  kernel::VirtualTimeExecutor ex;
  SensorRig rig(ex, {.mailbox = 4});
  ex.run_for(1ms);
  std::thread driver([&] {
    for (int i = 0; i < 10; ++i) {
      const float v[2] = {static_cast<float>(i), 0.0f};
      (void)rig.sensor->publish(v, kernel::Time{i});
    }
  });
  driver.join();
  ex.run_for(0ms);
  const auto got = rig.col->received();
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got.front().values[0], 6.0f);
  EXPECT_EQ(got.back().values[0], 9.0f);
  const SensorStats s = rig.sensor->stats();
  EXPECT_EQ(s.published, 10u);
  EXPECT_EQ(s.queued_total, 10u);
  EXPECT_EQ(s.overwritten, 6u);
  EXPECT_EQ(s.taken, 4u);
  EXPECT_EQ(sensor_warnings_containing(rig.node, "lost"), 1u);
}

TEST(Sensor, RejectsNaNAndWrongCountsAndCountsClosedAndUnheardSamples) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  const float good[2] = {1, 2};
  EXPECT_EQ(sensor->publish(good, kernel::Time{0}), PublishResult::kNotOpen);
  ASSERT_TRUE(sensor->open());
  EXPECT_EQ(sensor->publish(good, kernel::Time{1}), PublishResult::kUnheard);  // no task yet
  auto task = *node.create("ir_task", std::make_unique<SensorTask>(sensor));
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(task, *node.create("c", std::move(c))));
  ex.run_for(1ms);
  const float nan[2] = {1, std::numeric_limits<float>::quiet_NaN()};
  const float one[1] = {1};
  EXPECT_EQ(sensor->publish(nan, kernel::Time{2}), PublishResult::kRejected);
  EXPECT_EQ(sensor->publish(one, kernel::Time{3}), PublishResult::kRejected);
  EXPECT_EQ(sensor->publish(good, kernel::Time{4}), PublishResult::kQueued);
  ex.run_for(1ms);
  EXPECT_EQ(col->count(), 1u);  // the unheard sample was not forwarded late as if it were fresh
  const SensorStats s = sensor->stats();
  EXPECT_EQ(s.published, 5u);
  EXPECT_EQ(s.not_open, 1u);
  EXPECT_EQ(s.unheard, 1u);
  EXPECT_EQ(s.rejected, 2u);
  EXPECT_EQ(s.queued_total, 1u);
  EXPECT_EQ(s.published, s.not_open + s.unheard + s.rejected + s.queued_total);
  EXPECT_EQ(sensor->latest()->time, kernel::Time{4});
  EXPECT_EQ(sensor_warnings_containing(node, "rejected"), 1u);
}

TEST(Sensor, NotificationsForAGoneTaskOrNodeDoNothing) {
  kernel::VirtualTimeExecutor ex;
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  const float v[2] = {1, 2};
  {
    os::Node node(ex, {"bot"});
    auto task = *node.create("ir_task", std::make_unique<SensorTask>(sensor));
    ex.run_for(1ms);
    (void)sensor->publish(v, kernel::Time{0});  // a notification is now waiting in the executor
    ASSERT_TRUE(node.remove(task));
    EXPECT_FALSE(sensor->has_listener());
    ex.run_for(1ms);
    auto again = *node.create("ir_task2", std::make_unique<SensorTask>(sensor));
    (void)again;
    ex.run_for(1ms);
    (void)sensor->publish(v, kernel::Time{1});
  }  // the node goes with a notification still queued
  ex.run_for(1ms);
  EXPECT_FALSE(sensor->has_listener());
  const SensorStats s = sensor->stats();
  EXPECT_EQ(s.queued_total, 2u);
  EXPECT_EQ(s.overwritten, 2u);  // never taken: dropped when their task went
}

TEST(Sensor, FeedsOneTaskAtATime) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  (void)*node.create("a", std::make_unique<SensorTask>(sensor));
  ex.run_for(1ms);
  (void)*node.create("b", std::make_unique<SensorTask>(sensor));
  ex.run_for(1ms);
  bool said = false;
  for (const auto& e : node.log().since(0))
    if (e.source == "b" && e.level == os::LogLevel::kError && e.text.find("already feeds") != std::string::npos)
      said = true;
  EXPECT_TRUE(said);
}

TEST(Sensor, NarrowerTaskRangesClampWhatIsForwarded) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  SensorTask::Options o;
  o.ranges = *apply_ranges(sensor->channels(), "0:100");
  auto task = *node.create("ir_task", std::make_unique<SensorTask>(sensor, o));
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  ASSERT_TRUE(node.hook(task, *node.create("c", std::move(c))));
  ex.run_for(1ms);
  const float v[2] = {50, 500};
  (void)sensor->publish(v, kernel::Time{0});
  ex.run_for(1ms);
  ASSERT_EQ(col->count(), 1u);
  EXPECT_EQ(col->received()[0].values, (std::vector<float>{50, 100}));
}

// Keeps the numbers and the blob of every message.
class BlobKeeper final : public os::Task {
 public:
  std::vector<std::pair<std::vector<float>, std::shared_ptr<const os::Blob>>> seen;

 protected:
  void on_message(const os::Message& m) override {
    seen.push_back({{m.numbers().begin(), m.numbers().end()}, m.payload.blob});
  }
};

TEST(Sensor, ABlobTravelsWithItsNumbersSharedByEveryReceiver) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  SensorTask::Options o;
  o.ranges = *apply_ranges(sensor->channels(), "0:100");
  auto task = *node.create("ir_task", std::make_unique<SensorTask>(sensor, o));
  auto a = std::make_unique<BlobKeeper>(), b = std::make_unique<BlobKeeper>();
  BlobKeeper *ka = a.get(), *kb = b.get();
  ASSERT_TRUE(node.hook(task, *node.create("a", std::move(a))));
  ASSERT_TRUE(node.hook(task, *node.create("b", std::move(b))));
  ex.run_for(1ms);
  auto frame = std::make_shared<DepthImage>(4, 3);
  frame->ids[5] = 7;
  const float v[2] = {50, 500};
  EXPECT_EQ(sensor->publish(v, frame, kernel::Time{0}), PublishResult::kQueued);
  (void)sensor->publish(v, kernel::Time{1});  // and one without
  ex.run_for(1ms);
  for (const BlobKeeper* k : {ka, kb}) {
    ASSERT_EQ(k->seen.size(), 2u);
    EXPECT_EQ(k->seen[0].first, (std::vector<float>{50, 100}));  // narrowed like any sample
    EXPECT_EQ(k->seen[0].second.get(), frame.get());             // the one frame, not a copy
    const auto* image = os::blob_as<DepthImage>(k->seen[0].second.get());
    ASSERT_NE(image, nullptr);
    EXPECT_EQ(image->id_at(1, 1), 7);
    EXPECT_EQ(k->seen[1].second, nullptr);
  }
  EXPECT_EQ(sensor->latest()->blob, nullptr);  // the newest sample had none
}

TEST(Sensor, BadChannelTablesAreRefusedAtConstruction) {
  EXPECT_THROW(Sensor("s", {}), std::invalid_argument);
  EXPECT_THROW(Sensor("s", {{"a", "", 2, 1}}), std::invalid_argument);
  EXPECT_THROW(Sensor("s", ir_channels(), {.mailbox = 0}), std::invalid_argument);
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  SensorTask::Options o;
  o.ranges = {{"x", "", 0, 1}};
  EXPECT_THROW(SensorTask(sensor, o), std::invalid_argument);
}

TEST(Sensor, IoctlsListChannelsAndTheLatestSample) {
  auto sensor = std::make_shared<Sensor>("ir", ir_channels());
  EXPECT_EQ(*sensor->ioctl("channels"), "ir0 [0, 1023] raw\nir1 [0, 1023] raw\n");
  EXPECT_FALSE(sensor->ioctl("latest"));
  ASSERT_TRUE(sensor->open());
  const float v[2] = {3.5f, 2000};
  (void)sensor->publish(v, kernel::Time{7});
  EXPECT_EQ(*sensor->ioctl("latest"), "7 3.5 1023");
  EXPECT_NE(sensor->ioctl("stats")->find("unheard=1"), std::string::npos);
}

class ActivatedSensor final : public Sensor {
 public:
  ActivatedSensor() : Sensor("cam", {{"lum", "raw", 0, 1}}) {}
  int activations = 0, deactivations = 0;
  bool refuse = false;

 protected:
  kernel::Status activate() override {
    if (refuse) return kernel::Error{"no power"};
    ++activations;
    return {};
  }
  void deactivate() override { ++deactivations; }
};

TEST(Sensor, DriversStartAndStopWithTheDevice) {
  ActivatedSensor s;
  s.refuse = true;
  EXPECT_EQ(s.open().error(), "sensor 'cam' did not open: no power");
  EXPECT_FALSE(s.is_open());
  s.refuse = false;
  ASSERT_TRUE(s.open());
  ASSERT_TRUE(s.open());
  s.close();
  s.close();
  EXPECT_EQ(s.activations, 1);
  EXPECT_EQ(s.deactivations, 1);
}

}  // namespace
}  // namespace symb::robot
