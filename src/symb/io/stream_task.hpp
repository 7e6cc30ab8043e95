// StreamTask: a task that owns an IOStream and makes it hookable (the paper's UART0IOStreamTask).
// What the device delivers is sent to every task hooked to this one; what tasks send to it is
// written to the device. A reader thread of its own waits on the device (the io layer may use
// threads; tasks may not block) and hands each chunk to the node through Node::inject, so the
// same stream task works under the thread and the virtual-time executor.
//
// Modes decide what one outgoing message is:
//  - raw:    each chunk read, as it came (a terminal, a shell);
//  - lines:  each text line, without its '\n' (over-long lines are cut at max_line);
//  - frames: each good frame's payload (FrameCodec); bad frames are counted and dropped.
// Outgoing messages (port kDataPort) carry an io::Bytes blob. Incoming messages are written: a
// Bytes blob as it is (framed in frames mode); numbers as text "1 2.5 3\n" (raw, lines), or in
// frames mode as a number frame (see encode_numbers).
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/os/task.hpp"

namespace symb::io {

enum class StreamMode { kRaw, kLines, kFrames };

const char* to_string(StreamMode m);

// A frame that carries numbers: 'N', then each value as IEEE-754 float32, little-endian.
std::vector<std::byte> encode_numbers(std::span<const float> values);
// The numbers of a number frame, or nothing when `frame` is not one.
std::optional<std::vector<float>> decode_numbers(std::span<const std::byte> frame);

struct StreamStats {
  std::uint64_t bytes_in = 0;
  std::uint64_t bytes_out = 0;
  std::uint64_t chunks_in = 0;  // messages sent to hooked tasks
  std::uint64_t write_errors = 0;
  std::uint64_t lines_cut = 0;  // lines longer than max_line
  FrameStats frames;            // frames mode: the decoder's counters
  bool open = false;
};

class StreamTask : public os::Task {
 public:
  static constexpr os::Port kDataPort = 0;
  // Sent once, without a payload, after the last data when the stream stops delivering (end of
  // input, the device went away), and again after each reopening that is lost: a reader of
  // lines (a shell) hears here that no more will come, in order after what did.
  static constexpr os::Port kEndPort = 1;
  // Internal: chunks from the reader thread arrive on this port from outside any task.
  static constexpr os::Port kInboundPort = 0xffff;

  struct Options {
    StreamMode mode = StreamMode::kRaw;
    std::size_t max_line = 4096;
    std::size_t max_frame = 1024;
    kernel::Duration poll = std::chrono::milliseconds(20);  // how often the reader checks for stop
  };

  // The stream is shared: a device table (for the shell's ioctl) may hold it too.
  StreamTask(std::shared_ptr<IOStream> stream, Options options);
  ~StreamTask() override;

  IOStream& stream() { return *stream_; }
  // Counters, safe to read from any thread.
  StreamStats stats() const;

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_stop() override;

 private:
  struct Shared;
  struct Reader;
  void read_loop(std::shared_ptr<Shared> shared);
  // One pass of the reader: reports a closed stream (once), or reads what arrives within `wait`
  // and hands it to the node. False when the stream is closed. A target without threads (the
  // board, SYMB_BOARD) calls it from a periodic task instead of a reader thread.
  bool read_once(Reader& r, const std::shared_ptr<Shared>& shared, kernel::Duration wait);
  void write_out(std::span<const std::byte> bytes);

  std::shared_ptr<IOStream> stream_;
  Options options_;
  std::shared_ptr<Shared> shared_;
  std::thread reader_;
#ifdef SYMB_BOARD
  os::TaskId poller_;  // the reader task (`NAME.rx`) of a target without threads
#endif
  std::vector<std::byte> out_;
};

}  // namespace symb::io
