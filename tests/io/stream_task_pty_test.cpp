// StreamTask in frames mode over a real pseudo-terminal, under the thread executor: the board's
// shape (a task sends numbers to a UART stream task; the far end's stream task decodes the frames
// and hands them to the tasks hooked to it), with the kernel's serial layer in between.
#include <memory>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/io/pty_pair.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"

#include "io_test_support.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;

// Sends {n, n / 2, -n} on each tick, n = 1..count.
class NumberSender : public os::Task {
 public:
  explicit NumberSender(int count) : count_(count) {}

 protected:
  void on_tick() override {
    if (n_ >= count_) return;
    ++n_;
    const auto v = static_cast<float>(n_);
    send(0, {v, v / 2, -v});
  }

 private:
  int count_;
  int n_ = 0;
};

class FrameCollector : public os::Task {
 public:
  std::vector<std::vector<std::byte>> frames() const {
    std::lock_guard lock(mu_);
    return frames_;
  }
  std::size_t count() const {
    std::lock_guard lock(mu_);
    return frames_.size();
  }
  std::size_t without_bytes() const {
    std::lock_guard lock(mu_);
    return without_bytes_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    if (const Bytes* b = bytes_of(m))
      frames_.push_back(b->data);
    else
      ++without_bytes_;
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::vector<std::byte>> frames_;
  std::size_t without_bytes_ = 0;
};

TEST(StreamTaskOverPty, NumberFramesCrossARealSerialLineUnderTheThreadExecutor) {
  constexpr int kCount = 60;
  auto pty = PtyPair::open("uart");
  ASSERT_TRUE(pty) << pty.error();
  for (const auto& end : {pty->master, pty->slave}) ASSERT_TRUE(end->ioctl("baud", "115200"));

  kernel::ThreadExecutor ex;
  os::Node node(ex, {"board"});
  const StreamTask::Options frames{.mode = StreamMode::kFrames, .max_frame = 256};
  auto* near = new StreamTask(pty->master, frames);
  auto* far = new StreamTask(pty->slave, frames);
  auto a = node.create("uart.near", std::unique_ptr<os::Task>(near), {.queue_capacity = 128});
  auto b = node.create("uart.far", std::unique_ptr<os::Task>(far), {.queue_capacity = 128});
  auto c = std::make_unique<FrameCollector>();
  FrameCollector* col = c.get();
  auto rx = node.create("collector", std::move(c), {.queue_capacity = 128});
  ASSERT_TRUE(a && b && rx);
  ASSERT_TRUE(node.hook(*b, *rx));
  // Started only once hooked: a tick before the hook would send its number to nobody.
  auto tx = node.create("sender", std::make_unique<NumberSender>(kCount), {.period = 2ms, .autostart = false});
  ASSERT_TRUE(tx);
  ASSERT_TRUE(node.hook(*tx, *a));
  ASSERT_TRUE(node.start(*tx));

  ASSERT_TRUE(symb::testing::eventually([&] { return col->count() >= static_cast<std::size_t>(kCount); }))
      << "got " << col->count() << " of " << kCount << " frames";
  const auto got = col->frames();
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kCount));
  for (int i = 0; i < kCount; ++i) {
    auto values = decode_numbers(got[static_cast<std::size_t>(i)]);
    ASSERT_TRUE(values) << "frame " << i << " is not a number frame";
    const auto n = static_cast<float>(i + 1);
    EXPECT_EQ(*values, (std::vector<float>{n, n / 2, -n})) << "frame " << i;
  }
  EXPECT_EQ(col->without_bytes(), 0u);
  // The writer counts its bytes after write_all returns, which may be after the far end has them.
  EXPECT_TRUE(symb::testing::eventually([&] { return near->stats().bytes_out == far->stats().bytes_in; }))
      << near->stats().bytes_out << " bytes written, " << far->stats().bytes_in << " read";
  const StreamStats far_stats = far->stats();
  EXPECT_EQ(near->stats().write_errors, 0u);
  EXPECT_EQ(far_stats.frames.frames, static_cast<std::uint64_t>(kCount));
  EXPECT_EQ(far_stats.frames.dropped(), 0u);
  EXPECT_TRUE(far_stats.open);
  EXPECT_EQ(node.traffic().dropped(), 0u);
}

}  // namespace
}  // namespace symb::io
