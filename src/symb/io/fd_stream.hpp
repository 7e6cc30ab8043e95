// FdStream: an IOStream over POSIX file descriptors, the common ground of every driver whose
// device is a file descriptor (serial ports, pseudo-terminals, TCP sockets, stdin/stdout, CAN
// sockets). Reading waits with poll() and a timeout, writing loops until every byte is taken, and
// close() may be called from any thread: it wakes a reader or writer blocked on the device (the
// descriptors are never closed under a thread still using them, so a recycled descriptor number
// can never be read by mistake).
//
// WakeableFd is the piece underneath: the descriptors plus an eventfd that close() signals. It is
// public because other fd-based devices that are not streams (a TCP listener) need the same
// close-from-any-thread guarantee.
#pragma once

#include <poll.h>

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>
#include <span>
#include <string>

#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::io {

class WakeableFd {
 public:
  WakeableFd() = default;
  // Closes (see close()).
  ~WakeableFd();
  WakeableFd(const WakeableFd&) = delete;
  WakeableFd& operator=(const WakeableFd&) = delete;

  // Takes descriptors to watch: `read_fd` may equal `write_fd`, either may be -1 (that direction
  // is not there). With `owned` they are closed by close(); otherwise they are only let go.
  // Fails when descriptors are still attached or the wake-up eventfd cannot be made.
  kernel::Status attach(int read_fd, int write_fd, bool owned);
  // Wakes every thread waiting in wait(), waits until none is using the descriptors any more,
  // then closes (or lets go) them. Safe from any thread and more than once.
  void close();
  // Descriptors attached and not being closed.
  bool attached() const;

  // Proof that the descriptors stay open while it lives (close() waits for every Use to end).
  class Use {
   public:
    Use(Use&& o) noexcept : owner_(o.owner_), read_fd_(o.read_fd_), write_fd_(o.write_fd_), wake_fd_(o.wake_fd_) {
      o.owner_ = nullptr;
    }
    Use(const Use&) = delete;
    Use& operator=(const Use&) = delete;
    Use& operator=(Use&&) = delete;
    ~Use();
    int read_fd() const { return read_fd_; }
    int write_fd() const { return write_fd_; }

   private:
    friend class WakeableFd;
    Use(WakeableFd* owner, int r, int w, int wake) : owner_(owner), read_fd_(r), write_fd_(w), wake_fd_(wake) {}
    WakeableFd* owner_;
    int read_fd_;
    int write_fd_;
    int wake_fd_;
  };
  // A Use, or nothing when no descriptors are attached or they are being closed.
  std::optional<Use> use();

  enum class Wait { kReady, kTimeout, kClosed, kFailed };
  // Waits until `fd` reports one of `events` (POLLIN, POLLOUT), the timeout passes, or close() is
  // called. `revents` receives what poll() reported for `fd`; errno is kept on kFailed.
  static Wait wait(const Use& use, int fd, short events, kernel::Duration timeout, short& revents);

 private:
  mutable std::mutex mu_;
  std::condition_variable idle_cv_;
  int read_fd_ = -1;
  int write_fd_ = -1;
  int wake_fd_ = -1;
  bool owned_ = false;
  bool attached_ = false;
  bool closing_ = false;
  int users_ = 0;
};

class FdStream : public IOStream {
 public:
  ~FdStream() override;

  void close() override;
  bool is_open() const override;
  // Waits up to `timeout` for the first byte, then returns what one read() gives. End of stream
  // (the peer closed, a pseudo-terminal's other end went away) and device errors are errors, after
  // which is_open() is false until the stream is closed and opened again. When input and output
  // are separate descriptors (stdin and stdout), the end of the input stops only the input:
  // input_ended() is true, is_open() false, and write_all() goes on writing the output.
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override;
  // Writes everything or fails; gives up when the device takes no byte for write_timeout().
  kernel::Status write_all(std::span<const std::byte> data) override;

  // How long write_all() waits for a device that takes no more bytes (flow control, a full
  // socket buffer, a peer that does not read) before it reports an error.
  void set_write_timeout(kernel::Duration t);
  kernel::Duration write_timeout() const;
  // Why the stream stopped (end of stream, a device error), or empty while it works.
  std::string failure() const;
  // The input reached its end (see read_some); the output may still work.
  bool input_ended() const;

 protected:
  explicit FdStream(const std::string& name);
  // Hands the descriptors to the stream (see WakeableFd::attach). Owned descriptors are switched
  // to non-blocking; descriptors only borrowed (stdin/stdout) keep their mode, because the mode
  // belongs to the open file shared with other processes (a shell would see it change), and are
  // read and written only after poll() says they are ready, in pieces a pipe takes at once.
  kernel::Status attach(int read_fd, int write_fd, bool owned);
  // Runs `fn` with the descriptors held open (for tcsetattr and the like from ioctl handlers).
  template <class Fn>
  kernel::Status with_fd(Fn&& fn) {
    auto u = fd_.use();
    if (!u) return kernel::Error{"device '" + name() + "' is not open"};
    return fn(*u);
  }
  // Marks the stream broken (is_open() false) with a reason; the descriptors stay until close().
  void fail(std::string reason);
  // The same for a failure met while reading: with separate descriptors it stops the input only.
  void fail_input(std::string reason);
  bool output_failed() const;
  WakeableFd& fd() { return fd_; }

 private:
  kernel::Error closed_error() const;

  WakeableFd fd_;
  mutable std::mutex state_mu_;
  std::string failure_;
  std::string input_failure_;  // separate descriptors: why the input stopped
  bool separate_input_ = false;
  kernel::Duration write_timeout_ = std::chrono::seconds(2);
  bool write_is_socket_ = false;
  bool write_is_fifo_ = false;
  bool write_blocking_ = false;
};

}  // namespace symb::io
