#include "symb/io/fd_stream.hpp"

#include <fcntl.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <ctime>

namespace symb::io {

namespace {

std::string errno_text(int e) { return std::strerror(e); }

// Waits longer than this are treated as "forever": it keeps deadline arithmetic from
// overflowing when a caller passes Duration::max().
constexpr kernel::Duration kForever = std::chrono::hours(24 * 365);

std::chrono::steady_clock::time_point deadline_after(kernel::Duration d) {
  return std::chrono::steady_clock::now() + std::clamp(d, kernel::Duration::zero(), kForever);
}

timespec to_timespec(kernel::Duration d) {
  if (d < kernel::Duration::zero()) d = kernel::Duration::zero();
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(d.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(d.count() % 1'000'000'000);
  return ts;
}

// Writing to a pipe whose reader is gone raises SIGPIPE, which would kill the whole process (a
// board with a hundred robots) for one lost terminal. Sockets avoid it with MSG_NOSIGNAL; for
// pipes the signal is blocked in this thread for the write and a signal it raised is consumed,
// so the write fails with EPIPE instead and nothing process-wide (a signal disposition) changes.
class SigpipeBlock {
 public:
  SigpipeBlock() {
    sigset_t pending;
    sigemptyset(&pending);
    sigpending(&pending);
    was_pending_ = sigismember(&pending, SIGPIPE) == 1;
    sigset_t block;
    sigemptyset(&block);
    sigaddset(&block, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &block, &old_);
  }
  ~SigpipeBlock() {
    if (!was_pending_) {
      sigset_t pending;
      sigemptyset(&pending);
      sigpending(&pending);
      if (sigismember(&pending, SIGPIPE) == 1) {
        sigset_t only;
        sigemptyset(&only);
        sigaddset(&only, SIGPIPE);
        const timespec zero{};
        while (sigtimedwait(&only, nullptr, &zero) == -1 && errno == EINTR) {
        }
      }
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  SigpipeBlock(const SigpipeBlock&) = delete;
  SigpipeBlock& operator=(const SigpipeBlock&) = delete;

 private:
  sigset_t old_{};
  bool was_pending_ = false;
};

}  // namespace

// --- WakeableFd ----------------------------------------------------------------------------------

WakeableFd::~WakeableFd() {
  close();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

kernel::Status WakeableFd::attach(int read_fd, int write_fd, bool owned) {
  std::unique_lock lock(mu_);
  idle_cv_.wait(lock, [&] { return !closing_; });
  if (attached_) return kernel::Error{"descriptors already attached"};
  if (read_fd < 0 && write_fd < 0) return kernel::Error{"no descriptor to attach"};
  if (wake_fd_ < 0) {
    wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (wake_fd_ < 0) return kernel::Error{"cannot create an eventfd: " + errno_text(errno)};
  } else {
    // A close() before this attach left the wake-up signalled; reset it.
    std::uint64_t v = 0;
    while (::read(wake_fd_, &v, sizeof v) < 0 && errno == EINTR) {
    }
  }
  read_fd_ = read_fd;
  write_fd_ = write_fd;
  owned_ = owned;
  attached_ = true;
  return {};
}

void WakeableFd::close() {
  std::unique_lock lock(mu_);
  if (closing_) {
    idle_cv_.wait(lock, [&] { return !closing_; });
    return;
  }
  if (!attached_) return;
  closing_ = true;
  const std::uint64_t one = 1;
  while (::write(wake_fd_, &one, sizeof one) < 0 && errno == EINTR) {
  }
  idle_cv_.wait(lock, [&] { return users_ == 0; });
  if (owned_) {
    if (read_fd_ >= 0) ::close(read_fd_);
    if (write_fd_ >= 0 && write_fd_ != read_fd_) ::close(write_fd_);
  }
  read_fd_ = write_fd_ = -1;
  attached_ = false;
  closing_ = false;
  idle_cv_.notify_all();
}

bool WakeableFd::attached() const {
  std::lock_guard lock(mu_);
  return attached_ && !closing_;
}

std::optional<WakeableFd::Use> WakeableFd::use() {
  std::lock_guard lock(mu_);
  if (!attached_ || closing_) return std::nullopt;
  ++users_;
  return Use(this, read_fd_, write_fd_, wake_fd_);
}

WakeableFd::Use::~Use() {
  if (owner_ == nullptr) return;
  std::lock_guard lock(owner_->mu_);
  if (--owner_->users_ == 0) owner_->idle_cv_.notify_all();
}

WakeableFd::Wait WakeableFd::wait(const Use& use, int fd, short events, kernel::Duration timeout, short& revents) {
  revents = 0;
  const auto deadline = deadline_after(timeout);
  for (;;) {
    pollfd p[2] = {{fd, events, 0}, {use.wake_fd_, POLLIN, 0}};
    const timespec ts = to_timespec(deadline - std::chrono::steady_clock::now());
    const int n = ::ppoll(p, 2, &ts, nullptr);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Wait::kFailed;
    }
    if (p[1].revents != 0) return Wait::kClosed;
    if (p[0].revents != 0) {
      revents = p[0].revents;
      return Wait::kReady;
    }
    if (n == 0 && std::chrono::steady_clock::now() >= deadline) return Wait::kTimeout;
  }
}

// --- FdStream ------------------------------------------------------------------------------------

FdStream::FdStream(const std::string& name) : Device(name), IOStream(name) {}

FdStream::~FdStream() { fd_.close(); }

void FdStream::close() { fd_.close(); }

bool FdStream::is_open() const {
  if (!fd_.attached()) return false;
  std::lock_guard lock(state_mu_);
  return failure_.empty() && input_failure_.empty();
}

std::string FdStream::failure() const {
  std::lock_guard lock(state_mu_);
  return failure_.empty() ? input_failure_ : failure_;
}

bool FdStream::input_ended() const {
  std::lock_guard lock(state_mu_);
  return !input_failure_.empty() || !failure_.empty();
}

void FdStream::fail_input(std::string reason) {
  std::lock_guard lock(state_mu_);
  std::string& slot = separate_input_ ? input_failure_ : failure_;
  if (slot.empty()) slot = std::move(reason);
}

void FdStream::set_write_timeout(kernel::Duration t) {
  std::lock_guard lock(state_mu_);
  write_timeout_ = t;
}

kernel::Duration FdStream::write_timeout() const {
  std::lock_guard lock(state_mu_);
  return write_timeout_;
}

bool FdStream::output_failed() const {
  std::lock_guard lock(state_mu_);
  return !failure_.empty();
}

void FdStream::fail(std::string reason) {
  std::lock_guard lock(state_mu_);
  if (failure_.empty()) failure_ = std::move(reason);
}

kernel::Error FdStream::closed_error() const {
  std::string why = failure();
  return kernel::Error{"stream '" + name() + "' is " + (why.empty() ? std::string("closed") : "down: " + why)};
}

kernel::Status FdStream::attach(int read_fd, int write_fd, bool owned) {
  bool write_blocking = false, write_socket = false, write_fifo = false;
  for (int fd : {read_fd, write_fd}) {
    if (fd < 0) continue;
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags < 0) return kernel::Error{"device '" + name() + "': bad descriptor " + std::to_string(fd)};
    bool blocking = (flags & O_NONBLOCK) == 0;
    if (owned && blocking) {
      if (::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
        return kernel::Error{"device '" + name() + "': cannot make descriptor non-blocking: " + errno_text(errno)};
      blocking = false;
    }
    if (fd == write_fd) {
      write_blocking = blocking;
      struct stat st {};
      if (::fstat(fd, &st) == 0) {
        write_socket = S_ISSOCK(st.st_mode);
        write_fifo = S_ISFIFO(st.st_mode);
      }
    }
  }
  {
    std::lock_guard lock(state_mu_);
    write_blocking_ = write_blocking;
    write_is_socket_ = write_socket;
    write_is_fifo_ = write_fifo;
    separate_input_ = read_fd >= 0 && write_fd >= 0 && read_fd != write_fd;
    failure_.clear();
    input_failure_.clear();
  }
  if (auto st = fd_.attach(read_fd, write_fd, owned); !st)
    return kernel::Error{"device '" + name() + "': " + st.error()};
  return {};
}

kernel::Result<std::size_t> FdStream::read_some(std::span<std::byte> buf, kernel::Duration timeout) {
  auto use = fd_.use();
  if (!use || input_ended()) return closed_error();
  const int fd = use->read_fd();
  if (fd < 0) return kernel::Error{"stream '" + name() + "' cannot be read"};
  if (buf.empty()) return std::size_t{0};
  const auto deadline = deadline_after(timeout);
  for (;;) {
    short revents = 0;
    switch (WakeableFd::wait(*use, fd, POLLIN, deadline - std::chrono::steady_clock::now(), revents)) {
      case WakeableFd::Wait::kClosed: return kernel::Error{"stream '" + name() + "' is closed"};
      case WakeableFd::Wait::kTimeout: return std::size_t{0};
      case WakeableFd::Wait::kFailed: {
        std::string why = "poll failed: " + errno_text(errno);
        fail_input(why);
        return kernel::Error{"stream '" + name() + "': " + why};
      }
      case WakeableFd::Wait::kReady: break;
    }
    if ((revents & POLLNVAL) != 0) {
      fail_input("descriptor not valid");
      return closed_error();
    }
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) {
      fail_input("end of stream");
      return closed_error();
    }
    const int e = errno;
    // Readiness can be spurious; the next wait returns at the deadline at the latest.
    if (e == EINTR || e == EAGAIN || e == EWOULDBLOCK) continue;
    // A pseudo-terminal reports its other end going away as EIO.
    fail_input(e == EIO ? "end of stream (the other end is gone)" : "read failed: " + errno_text(e));
    return closed_error();
  }
}

kernel::Status FdStream::write_all(std::span<const std::byte> data) {
  auto use = fd_.use();
  if (!use || output_failed()) return closed_error();
  const int fd = use->write_fd();
  if (fd < 0) return kernel::Error{"stream '" + name() + "' cannot be written"};
  bool blocking = false, socket = false, fifo = false;
  kernel::Duration patience{};
  {
    std::lock_guard lock(state_mu_);
    blocking = write_blocking_;
    socket = write_is_socket_;
    fifo = write_is_fifo_;
    patience = write_timeout_;
  }
  std::optional<SigpipeBlock> sigpipe;
  if (fifo) sigpipe.emplace();  // terminals report a lost peer as EIO, sockets get MSG_NOSIGNAL
  auto stalled = [&] {
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(patience).count();
    return kernel::Error{"stream '" + name() + "': device took no byte for " + std::to_string(ms) + " ms"};
  };
  auto deadline = deadline_after(patience);
  while (!data.empty()) {
    if (blocking) {
      // A blocking descriptor is written only when poll says there is room, and at most
      // PIPE_BUF bytes at a time: that much fits a pipe that polls writable, so the write
      // returns at once and close() never waits behind it.
      short revents = 0;
      const auto w = WakeableFd::wait(*use, fd, POLLOUT, deadline - std::chrono::steady_clock::now(), revents);
      if (w == WakeableFd::Wait::kClosed) return kernel::Error{"stream '" + name() + "' is closed"};
      if (w == WakeableFd::Wait::kTimeout) return stalled();
      if (w == WakeableFd::Wait::kFailed) return kernel::Error{"stream '" + name() + "': poll failed"};
    }
    const std::size_t chunk = blocking ? std::min<std::size_t>(data.size(), PIPE_BUF) : data.size();
    const ssize_t n = socket ? ::send(fd, data.data(), chunk, MSG_NOSIGNAL) : ::write(fd, data.data(), chunk);
    if (n > 0) {
      data = data.subspan(static_cast<std::size_t>(n));
      deadline = deadline_after(patience);
      continue;
    }
    const int e = n < 0 ? errno : EAGAIN;
    if (e == EINTR) continue;
    if (e == EAGAIN || e == EWOULDBLOCK || e == ENOBUFS) {
      // ENOBUFS (a full CAN transmit queue) is not signalled by poll: retry after a short wait
      // on the wake-up alone, so close() still ends it at once.
      short revents = 0;
      const auto left = deadline - std::chrono::steady_clock::now();
      const auto w =
          e == ENOBUFS
              ? WakeableFd::wait(*use, -1, 0, std::min<kernel::Duration>(left, std::chrono::milliseconds(1)), revents)
              : WakeableFd::wait(*use, fd, POLLOUT, left, revents);
      if (w == WakeableFd::Wait::kClosed) return kernel::Error{"stream '" + name() + "' is closed"};
      if (std::chrono::steady_clock::now() >= deadline) return stalled();
      continue;
    }
    fail(e == EPIPE || e == ECONNRESET || e == EIO ? "the other end is gone (" + errno_text(e) + ")"
                                                   : "write failed: " + errno_text(e));
    return closed_error();
  }
  return {};
}

}  // namespace symb::io
