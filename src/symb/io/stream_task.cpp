#include "symb/io/stream_task.hpp"

#include <bit>
#include <charconv>
#include <cstring>
#include <functional>
#include <mutex>
#include <thread>

#include "symb/io/bytes.hpp"
#include "symb/io/number_text.hpp"
#include "symb/os/node.hpp"

namespace symb::io {

const char* to_string(StreamMode m) {
  switch (m) {
    case StreamMode::kRaw: return "raw";
    case StreamMode::kLines: return "lines";
    case StreamMode::kFrames: return "frames";
  }
  return "?";
}

std::vector<std::byte> encode_numbers(std::span<const float> values) {
  std::vector<std::byte> out;
  out.reserve(1 + 4 * values.size());
  out.push_back(std::byte{'N'});
  for (float v : values) {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::byte>((bits >> (8 * i)) & 0xff));
  }
  return out;
}

std::optional<std::vector<float>> decode_numbers(std::span<const std::byte> frame) {
  if (frame.empty() || frame[0] != std::byte{'N'} || (frame.size() - 1) % 4 != 0) return std::nullopt;
  std::vector<float> v((frame.size() - 1) / 4);
  for (std::size_t k = 0; k < v.size(); ++k) {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i)
      bits |= static_cast<std::uint32_t>(frame[1 + 4 * k + static_cast<std::size_t>(i)]) << (8 * i);
    v[k] = std::bit_cast<float>(bits);
  }
  return v;
}

// What the reader thread and the task share. The reader's injected work holds it weakly, so
// work still queued in a virtual-time executor after the task is gone does nothing.
struct StreamTask::Shared {
  os::Node* node = nullptr;
  os::TaskId self;
  std::atomic<bool> stop{false};
  mutable std::mutex mu;  // guards stats
  StreamStats stats;
};

StreamTask::StreamTask(std::shared_ptr<IOStream> stream, Options options)
    : stream_(std::move(stream)), options_(options), shared_(std::make_shared<Shared>()) {}

StreamTask::~StreamTask() {
  // on_stop joined the reader; this covers a task destroyed without ever being started.
  shared_->stop = true;
  if (reader_.joinable()) reader_.join();
}

StreamStats StreamTask::stats() const {
  std::lock_guard lock(shared_->mu);
  StreamStats s = shared_->stats;
  s.open = stream_->is_open();
  return s;
}

#ifdef SYMB_BOARD
namespace {
// A target without threads reads its stream from a periodic task (`NAME.rx`) that makes the
// reader's passes, where Linux has a reader thread.
class StreamPollTask final : public os::Task {
 public:
  explicit StreamPollTask(std::function<void()> poll) : poll_(std::move(poll)) {}

 protected:
  void on_tick() override { poll_(); }

 private:
  std::function<void()> poll_;
};
}  // namespace
#endif

// What one reader keeps between its passes. A board's reader takes what its UART's ring holds
// every few milliseconds: a small buffer does (and RAM is 32 KiB there).
#ifdef SYMB_BOARD
constexpr std::size_t kReadChunk = 256;
#else
constexpr std::size_t kReadChunk = 4096;
#endif
struct StreamTask::Reader {
  explicit Reader(std::size_t max_frame) : decoder(max_frame), buf(kReadChunk) {}
  FrameDecoder decoder;
  std::string line;
  bool cutting = false;
  std::vector<std::byte> buf;
  bool reported_closed = false;
};

void StreamTask::on_start() {
  shared_->node = &node();
  shared_->self = id();
  if (!stream_->is_open())
    if (auto st = stream_->open(); !st)
      log(os::LogLevel::kWarn, "cannot open '" + stream_->name() + "': " + st.error());
#ifdef SYMB_BOARD
  // The frame decoder's buffers only where frames come (a shell's raw line needs none).
  auto reader = std::make_shared<Reader>(options_.mode == StreamMode::kFrames ? options_.max_frame : 0);
  os::TaskOptions o;
  o.period = options_.poll;
  o.priority = node().info(id())->priority;
  o.queue_capacity = 1;  // it is sent nothing
  auto poller = node().create(name() + ".rx", std::make_unique<StreamPollTask>([this, reader, s = shared_] {
                                (void)read_once(*reader, s, kernel::Duration{0});
                              }),
                              o);
  if (!poller) log(os::LogLevel::kError, "no reader task: " + poller.error());
  poller_ = poller ? *poller : os::TaskId{};
#else
  reader_ = std::thread([this, s = shared_] { read_loop(s); });
#endif
}

void StreamTask::on_stop() {
  shared_->stop = true;
#ifdef SYMB_BOARD
  if (poller_.valid()) (void)node().remove(poller_);
#endif
  if (reader_.joinable()) reader_.join();
}

void StreamTask::read_loop(std::shared_ptr<Shared> shared) {
  Reader r(options_.max_frame);
  while (!shared->stop.load())
    if (!read_once(r, shared, options_.poll)) std::this_thread::sleep_for(options_.poll);
}

bool StreamTask::read_once(Reader& r, const std::shared_ptr<Shared>& shared, kernel::Duration wait) {
  std::weak_ptr<Shared> weak = shared;
  if (!stream_->is_open()) {
    // A lost link is reported once, then polled: the board keeps running through it.
    if (!r.reported_closed) {
      r.reported_closed = true;
      os::Node* n = shared->node;
      std::string name = stream_->name();
      n->inject([weak, name] {
        auto s = weak.lock();
        if (!s) return;
        s->node->log().warn(name, "stream closed");
        // Through this task's own queue, so that it follows the data injected before it.
        os::Message m;
        m.port = kEndPort;
        (void)s->node->post(s->self, m, os::QueuePolicy::kRefuse);
      });
    }
    return false;
  }
  r.reported_closed = false;  // open again (reopened): its next loss is reported anew
  auto got = stream_->read_some(r.buf, wait);
  if (!got || *got == 0) return true;
  std::span<const std::byte> chunk(r.buf.data(), *got);
  std::vector<os::Payload> out;
  std::uint64_t cut = 0;
  switch (options_.mode) {
    case StreamMode::kRaw: out.push_back(bytes_payload(chunk)); break;
    case StreamMode::kLines:
      for (std::byte b : chunk) {
        if (b == std::byte{'\n'}) {
          if (!r.line.empty() && r.line.back() == '\r') r.line.pop_back();
          out.push_back(text_payload(r.line));
          r.line.clear();
          r.cutting = false;
        } else if (r.line.size() < options_.max_line) {
          r.line.push_back(static_cast<char>(b));
        } else if (!r.cutting) {
          r.cutting = true;  // the rest of an over-long line is dropped, and counted once
          ++cut;
        }
      }
      break;
    case StreamMode::kFrames:
      r.decoder.feed(chunk, [&](std::span<const std::byte> frame) { out.push_back(bytes_payload(frame)); });
      break;
  }
  {
    std::lock_guard lock(shared->mu);
    shared->stats.bytes_in += chunk.size();
    shared->stats.chunks_in += out.size();
    shared->stats.lines_cut += cut;
    shared->stats.frames = r.decoder.stats();
  }
  if (out.empty()) return true;
  shared->node->inject([weak, out = std::move(out)] {
    auto s = weak.lock();
    if (!s) return;
    for (const auto& p : out) {
      os::Message m;
      m.port = kInboundPort;
      m.payload = p;
      (void)s->node->post(s->self, m, os::QueuePolicy::kRefuse);
    }
  });
  return true;
}

void StreamTask::write_out(std::span<const std::byte> bytes) {
  if (bytes.empty()) return;
  auto st = stream_->write_all(bytes);
  std::lock_guard lock(shared_->mu);
  if (st)
    shared_->stats.bytes_out += bytes.size();
  else
    ++shared_->stats.write_errors;
}

void StreamTask::on_message(const os::Message& m) {
  if (m.port == kInboundPort && !m.source.valid()) {
    send(kDataPort, m.payload);
    return;
  }
  if (m.port == kEndPort && !m.source.valid()) {
    send(kEndPort, m.payload);
    return;
  }
  out_.clear();
  if (const Bytes* b = bytes_of(m)) {
    if (options_.mode == StreamMode::kFrames)
      encode_frame(b->data, out_);
    else
      out_.assign(b->data.begin(), b->data.end());
  } else if (options_.mode == StreamMode::kFrames) {
    encode_frame(encode_numbers(m.numbers()), out_);
  } else {
    std::string text = format_numbers(m.numbers());
    text.push_back('\n');
    out_.assign(reinterpret_cast<const std::byte*>(text.data()),
                reinterpret_cast<const std::byte*>(text.data()) + text.size());
  }
  write_out(out_);
}

}  // namespace symb::io
