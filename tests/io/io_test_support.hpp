// Helpers shared by the fd-based stream tests: telling when another thread is really blocked in
// the kernel, and moving bytes and frames across a stream with a writer thread and a reading loop.
#pragma once

#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <functional>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"

#include "support/eventually.hpp"

namespace symb::io::testing {

using namespace std::chrono_literals;

// Generous: a TSan build runs about ten times slower than a normal one.
inline constexpr auto kDeadline = 20s;

inline pid_t this_thread_tid() { return static_cast<pid_t>(::syscall(SYS_gettid)); }

// True when thread `tid` of this process sleeps in the kernel (state 'S'): a reader is then
// inside its poll, which is what a "close wakes the reader" test must interrupt.
inline bool thread_sleeping(pid_t tid) {
  std::ifstream f("/proc/self/task/" + std::to_string(tid) + "/stat");
  std::string line;
  if (!std::getline(f, line)) return false;
  const auto paren = line.rfind(')');
  return paren != std::string::npos && paren + 2 < line.size() && line[paren + 2] == 'S';
}

// Reads from `in` until `want` bytes came or the deadline passed.
// Blocks a reader thread in stream.read_some(), proves it really sleeps in the kernel, closes the
// stream from this thread and checks that the reader returned promptly with a "closed" error.
inline void expect_close_wakes_blocked_reader(InputDevice& stream) {
  std::atomic<pid_t> tid{0};
  std::atomic<bool> returned{false};
  std::string error;
  std::chrono::steady_clock::duration took{};
  std::thread reader([&] {
    tid = this_thread_tid();
    std::byte buf[64];
    const auto t0 = std::chrono::steady_clock::now();
    auto r = stream.read_some(buf, 60s);
    took = std::chrono::steady_clock::now() - t0;
    if (!r) error = r.error();
    returned = true;
  });
  const bool blocked = symb::testing::eventually([&] { return tid.load() != 0 && thread_sleeping(tid.load()); });
  EXPECT_TRUE(blocked) << "the reader never blocked";
  EXPECT_FALSE(returned.load());
  stream.close();
  reader.join();
  EXPECT_LT(took, 10s) << "close did not wake the reader";
  EXPECT_NE(error.find("closed"), std::string::npos) << error;
  EXPECT_FALSE(stream.is_open());
}

inline std::vector<std::byte> read_exactly(InputDevice& in, std::size_t want,
                                           std::chrono::nanoseconds limit = kDeadline) {
  std::vector<std::byte> got;
  std::vector<std::byte> buf(4096);
  const auto end = std::chrono::steady_clock::now() + limit;
  while (got.size() < want && std::chrono::steady_clock::now() < end) {
    auto n = in.read_some(buf, 50ms);
    if (!n) break;
    got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*n));
  }
  return got;
}

// Writes `wire` to `out` from a thread of its own, in pieces of 1 to `piece` bytes, while the
// caller reads; join() returns the first write error, or an empty string.
class Writer {
 public:
  Writer(OutputDevice& out, std::vector<std::byte> wire, std::size_t piece = 777)
      : thread_([this, &out, wire = std::move(wire), piece] {
          std::span<const std::byte> rest(wire);
          std::size_t k = 0;
          while (!rest.empty()) {
            const std::size_t n = std::min(rest.size(), 1 + (7919 * ++k) % piece);
            if (auto st = out.write_all(rest.first(n)); !st) {
              std::lock_guard lock(mu_);
              error_ = st.error();
              return;
            }
            rest = rest.subspan(n);
          }
        }) {}
  ~Writer() {
    if (thread_.joinable()) thread_.join();
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  std::string join() {
    if (thread_.joinable()) thread_.join();
    std::lock_guard lock(mu_);
    return error_;
  }

 private:
  std::mutex mu_;
  std::string error_;
  std::thread thread_;
};

// Reads frames from `in` into `decoder` until `count` frames came or the deadline passed.
inline std::vector<std::vector<std::byte>> read_frames(InputDevice& in, FrameDecoder& decoder, std::size_t count,
                                                       std::chrono::nanoseconds limit = kDeadline) {
  std::vector<std::vector<std::byte>> frames;
  std::vector<std::byte> buf(4096);
  const auto end = std::chrono::steady_clock::now() + limit;
  while (frames.size() < count && std::chrono::steady_clock::now() < end) {
    auto n = in.read_some(buf, 50ms);
    if (!n) break;
    decoder.feed(std::span<const std::byte>(buf.data(), *n),
                 [&](std::span<const std::byte> f) { frames.emplace_back(f.begin(), f.end()); });
  }
  return frames;
}

}  // namespace symb::io::testing
