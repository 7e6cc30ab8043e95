#include "symb/apps/view/frame_queue.hpp"

#include <stdexcept>

namespace symb::apps::view {

FrameQueue::FrameQueue(std::size_t capacity) : capacity_(capacity) {
  if (capacity == 0) throw std::invalid_argument("FrameQueue: capacity must be at least 1");
}

void FrameQueue::push(std::string frame) {
  std::string overtaken;  // freed outside the lock
  {
    std::lock_guard lock(mu_);
    if (closed_) return;
    ++stats_.pushed;
    if (frames_.size() == capacity_) {
      overtaken = std::move(frames_.front());
      frames_.pop_front();
      ++stats_.dropped;
    }
    frames_.push_back(std::move(frame));
  }
  ready_.notify_one();
}

std::optional<std::string> FrameQueue::pop(kernel::Duration timeout) {
  std::unique_lock lock(mu_);
  if (!ready_.wait_for(lock, timeout, [this] { return closed_ || !frames_.empty(); }) || closed_) return std::nullopt;
  std::string frame = std::move(frames_.front());
  frames_.pop_front();
  writing_ = true;
  return frame;
}

void FrameQueue::done(bool written) {
  std::lock_guard lock(mu_);
  if (!writing_) return;
  writing_ = false;
  ++(written ? stats_.sent : stats_.dropped);
}

void FrameQueue::close() {
  {
    std::lock_guard lock(mu_);
    closed_ = true;
    stats_.dropped += frames_.size();  // never sent: the counters still close
    frames_.clear();
  }
  ready_.notify_all();
}

bool FrameQueue::closed() const {
  std::lock_guard lock(mu_);
  return closed_;
}

FrameQueueStats FrameQueue::stats() const {
  std::lock_guard lock(mu_);
  FrameQueueStats s = stats_;
  s.queued = frames_.size() + (writing_ ? 1 : 0);
  return s;
}

}  // namespace symb::apps::view
