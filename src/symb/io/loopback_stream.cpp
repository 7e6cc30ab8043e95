#include "symb/io/loopback_stream.hpp"

#include <condition_variable>
#include <deque>
#include <mutex>

namespace symb::io {

namespace {

// One direction of the pair.
struct Pipe {
  explicit Pipe(std::size_t cap) : capacity(cap) {}
  std::mutex mu;
  std::condition_variable cv;
  std::deque<std::byte> bytes;
  std::size_t capacity;
  bool writer_closed = false;
  bool reader_closed = false;
};

class LoopbackEnd final : public IOStream {
 public:
  LoopbackEnd(std::string name, std::shared_ptr<Pipe> in, std::shared_ptr<Pipe> out)
      : Device(name), IOStream(name), in_(std::move(in)), out_(std::move(out)) {}
  ~LoopbackEnd() override { close(); }

  kernel::Status open() override { return is_open() ? kernel::Status{} : kernel::Error{"loopback cannot reopen"}; }
  void close() override {
    for (auto* p : {in_.get(), out_.get()}) {
      std::lock_guard lock(p->mu);
      (p == in_.get() ? p->reader_closed : p->writer_closed) = true;
      p->cv.notify_all();
    }
  }
  bool is_open() const override {
    std::lock_guard lock(in_->mu);
    return !in_->reader_closed && !(in_->writer_closed && in_->bytes.empty());
  }

  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override {
    std::unique_lock lock(in_->mu);
    in_->cv.wait_for(lock, timeout, [&] { return !in_->bytes.empty() || in_->writer_closed || in_->reader_closed; });
    if (in_->reader_closed) return kernel::Error{"stream '" + name() + "' is closed"};
    if (in_->bytes.empty()) {
      if (in_->writer_closed) return kernel::Error{"stream '" + name() + "': end of stream"};
      return std::size_t{0};
    }
    const std::size_t n = std::min(buf.size(), in_->bytes.size());
    std::copy_n(in_->bytes.begin(), n, buf.begin());
    in_->bytes.erase(in_->bytes.begin(), in_->bytes.begin() + static_cast<std::ptrdiff_t>(n));
    in_->cv.notify_all();
    return n;
  }

  kernel::Status write_all(std::span<const std::byte> data) override {
    std::unique_lock lock(out_->mu);
    while (!data.empty()) {
      if (!out_->cv.wait_for(lock, std::chrono::seconds(1), [&] {
            return out_->bytes.size() < out_->capacity || out_->reader_closed || out_->writer_closed;
          }))
        return kernel::Error{"stream '" + name() + "': peer not reading"};
      if (out_->reader_closed || out_->writer_closed) return kernel::Error{"stream '" + name() + "' is closed"};
      const std::size_t n = std::min(data.size(), out_->capacity - out_->bytes.size());
      out_->bytes.insert(out_->bytes.end(), data.begin(), data.begin() + static_cast<std::ptrdiff_t>(n));
      data = data.subspan(n);
      out_->cv.notify_all();
    }
    return {};
  }

 private:
  std::shared_ptr<Pipe> in_;
  std::shared_ptr<Pipe> out_;
};

}  // namespace

std::pair<std::unique_ptr<IOStream>, std::unique_ptr<IOStream>> make_loopback_pair(const std::string& name,
                                                                                   std::size_t capacity) {
  auto ab = std::make_shared<Pipe>(capacity);
  auto ba = std::make_shared<Pipe>(capacity);
  return {std::make_unique<LoopbackEnd>(name + ".a", ba, ab), std::make_unique<LoopbackEnd>(name + ".b", ab, ba)};
}

}  // namespace symb::io
