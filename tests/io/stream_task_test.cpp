#include "symb/io/stream_task.hpp"

#include <thread>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;

class TextCollector : public os::Task {
 public:
  std::vector<std::string> texts() const {
    std::lock_guard lock(mu_);
    return texts_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    if (const Bytes* b = bytes_of(m)) texts_.emplace_back(b->text());
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::string> texts_;
};

// Drives a virtual-time node until `done` or a real-time deadline: the data comes from threads.
template <class F>
bool pump(kernel::VirtualTimeExecutor& ex, F done) {
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (!done() && std::chrono::steady_clock::now() < end) {
    ex.wait_injected(5ms);
    ex.run_for(1ms);
  }
  return done();
}

TEST(StreamTask, LinesFromTheDeviceReachHookedTasksUnderVirtualTime) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"board"});
  auto [ours, theirs] = make_loopback_pair("uart");
  std::shared_ptr<IOStream> dev = std::move(ours);
  auto stream = *node.create(
      "uart0", std::make_unique<StreamTask>(dev, StreamTask::Options{.mode = StreamMode::kLines, .max_line = 8}));
  auto c = std::make_unique<TextCollector>();
  TextCollector* col = c.get();
  auto rx = *node.create("rx", std::move(c));
  ASSERT_TRUE(node.hook(stream, rx));
  ex.run_for(1ms);
  ASSERT_TRUE(theirs->write_all(as_bytes("hello\r\nwor")));
  ASSERT_TRUE(theirs->write_all(as_bytes("ld\nthis line is too long\n")));
  ASSERT_TRUE(pump(ex, [&] { return col->texts().size() == 3; }));
  EXPECT_EQ(col->texts(), (std::vector<std::string>{"hello", "world", "this lin"}));
}

TEST(StreamTask, MessagesToTheTaskAreWrittenOut) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"board"});
  auto [ours, theirs] = make_loopback_pair("uart");
  std::shared_ptr<IOStream> dev = std::move(ours);
  auto stream = *node.create("uart0", std::make_unique<StreamTask>(dev, StreamTask::Options{.mode = StreamMode::kRaw}));
  ex.run_for(1ms);
  os::Message m;
  m.payload = text_payload("ping ");
  ASSERT_TRUE(node.post(stream, m));
  os::Message n;
  n.payload = os::Payload{1.5f, 2.0f};
  ASSERT_TRUE(node.post(stream, n));
  ex.run_for(1ms);
  auto line = theirs->read_line(2s);
  ASSERT_TRUE(line);
  EXPECT_EQ(line->value(), "ping 1.5 2");
}

TEST(StreamTask, NumberFramesCrossAStreamBetweenTwoNodes) {
  kernel::ThreadExecutor ex;
  os::Node sim(ex, {"sim"});
  os::Node board(ex, {"board"});
  auto [a, b] = make_loopback_pair("serial");
  std::shared_ptr<IOStream> sa = std::move(a), sb = std::move(b);
  auto out = *sim.create("tx", std::make_unique<StreamTask>(sa, StreamTask::Options{.mode = StreamMode::kFrames}));
  auto rx_task = std::make_unique<StreamTask>(sb, StreamTask::Options{.mode = StreamMode::kFrames});
  StreamTask* rx = rx_task.get();
  auto in = *board.create("rx", std::move(rx_task));
  auto c = std::make_unique<TextCollector>();
  TextCollector* col = c.get();
  auto sink = *board.create("sink", std::move(c));
  ASSERT_TRUE(board.hook(in, sink));
  for (int i = 0; i < 5; ++i) {
    os::Message m;
    m.payload = os::Payload{static_cast<float>(i), 0.25f, -3.0f};
    ASSERT_TRUE(sim.post(out, m));
  }
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (col->texts().size() < 5 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
  auto frames = col->texts();
  ASSERT_EQ(frames.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    const auto& f = frames[static_cast<std::size_t>(i)];
    auto v = decode_numbers({reinterpret_cast<const std::byte*>(f.data()), f.size()});
    ASSERT_TRUE(v);
    EXPECT_EQ(*v, (std::vector<float>{static_cast<float>(i), 0.25f, -3.0f}));
  }
  const StreamStats st = rx->stats();
  EXPECT_EQ(st.frames.frames, 5u);
  EXPECT_EQ(st.frames.dropped(), 0u);
  EXPECT_EQ(st.chunks_in, 5u);
}

TEST(StreamTask, NumberFrameCodec) {
  const std::vector<float> v = {0.0f, -1.0f, 3.5e10f};
  auto enc = encode_numbers(v);
  EXPECT_EQ(enc.size(), 13u);
  EXPECT_EQ(*decode_numbers(enc), v);
  EXPECT_FALSE(decode_numbers({}));
  enc.pop_back();
  EXPECT_FALSE(decode_numbers(enc));
}

}  // namespace
}  // namespace symb::io
