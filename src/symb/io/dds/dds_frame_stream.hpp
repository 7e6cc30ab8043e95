// DdsFrameStream: a byte stream (io::IOStream) over a pair of Cyclone DDS topics, for protocols
// made for a serial line that must cross processes and machines instead: the hardware-in-the-loop
// frames of a split world (sim/hil_split_world.hpp: `symb run --bus dds --remote`, `symb serve
// --scenario`). Each write_all() is one sample (symb/msg/FrameChunk, io/dds/FrameChunk.idl), read
// back as bytes in order; the frames inside keep their own checksums, so bytes from a foreign
// writer on the topic are counted and dropped by the frame decoder above, as line noise is.
//
// On the wire: reliable, keep-all, volatile, automatic liveliness with a lease (the DDS bus's QoS,
// dds_participant.hpp); topics after ROS 2's conventions, rt/<prefix>/<channel>/<direction>. Peers
// find each other by DDS discovery with no configuration.
//
// The peer (the writers on the read topic) is watched by liveliness: it is kAlive once one
// asserted it, kLost when its lease ran out (the process was killed, hung or cut off) and kLeft
// when its writer was deleted (the process ended). Once the peer is gone and everything it sent
// was read, read_some() fails with the reason and is_open() is false: the end of stream a serial
// line reports when its other end goes away. A writer that comes later (a restarted process, or a
// foreign one that came and went first) makes the stream open again, as a line's device that comes
// back does; the protocol above decides what a gone peer means.
//
// Threads: one reader and one writer at a time, as io::IOStream says; DDS's listener threads only
// fill the stream's buffer. DdsFrameLinks holds the process's participant: it outlives its streams
// (they keep it alive).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::io {

struct DdsFrameOptions {
  std::uint32_t domain = 0;     // DDS domain id (0..232); a test picks its own so runs do not meet
  std::string prefix = "symb";  // the first name of every topic: rt/<prefix>/...
  kernel::Duration lease = std::chrono::milliseconds(1000);  // a silent peer is lost after it
};

enum class DdsPeerState : std::uint8_t { kWaiting, kAlive, kLost, kLeft };
const char* to_string(DdsPeerState s);

struct DdsFrameStreamCounts {
  std::uint64_t chunks_written = 0, bytes_written = 0;
  std::uint64_t chunks_read = 0, bytes_read = 0;
  std::uint64_t write_errors = 0;  // writes DDS refused
  std::uint64_t peers_lost = 0;    // writers on the read topic whose lease ran out
  std::uint64_t peers_left = 0;    // ... that were deleted (a clean end)
};

class DdsFrameStream;

class DdsFrameLinks : public std::enable_shared_from_this<DdsFrameLinks> {
 public:
  struct Core;
  // Fails when DDS cannot make a participant on the domain (the DDS error text), for a domain
  // above 232, an empty prefix or a lease that is not positive.
  static kernel::Result<std::shared_ptr<DdsFrameLinks>> create(DdsFrameOptions options);
  ~DdsFrameLinks();
  DdsFrameLinks(const DdsFrameLinks&) = delete;
  DdsFrameLinks& operator=(const DdsFrameLinks&) = delete;

  // rt/<prefix>/<channel>/<direction>, each part made a DDS name ('.' and '-' become '_').
  std::string topic(std::string_view channel, std::string_view direction) const;
  // A stream writing topic(channel, out) and reading topic(channel, in). Fails when DDS refuses
  // a topic, reader or writer.
  kernel::Result<std::shared_ptr<DdsFrameStream>> stream(std::string_view channel, std::string_view out,
                                                         std::string_view in);
  const DdsFrameOptions& options() const { return options_; }

 private:
  explicit DdsFrameLinks(DdsFrameOptions options);
  DdsFrameOptions options_;
  std::unique_ptr<Core> core_;
};

class DdsFrameStream final : public IOStream {
 public:
  struct State;  // shared with DDS's listener threads (defined in the .cpp)
  ~DdsFrameStream() override;

  // Nothing to open: the DDS entities exist from the start. A stream closed by close() stays
  // closed.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override;
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override;
  // One sample. Nothing waits for a reader: with none matched the bytes are gone, as on a line
  // with no one at the other end.
  kernel::Status write_all(std::span<const std::byte> data) override;

  DdsPeerState peer() const;
  // Until the writer has a reader and the reader a live writer, or `timeout`. False on timeout.
  bool wait_matched(kernel::Duration timeout) const;
  // Until every reader acknowledged every sample written, or `timeout`; before a clean end.
  bool flush(kernel::Duration timeout) const;
  // Deletes the writer: the peer sees this end leave (kLeft) rather than get lost.
  void finish_sending();
  DdsFrameStreamCounts counts() const;
  const std::string& read_topic() const { return read_topic_; }
  const std::string& write_topic() const { return write_topic_; }

 private:
  friend class DdsFrameLinks;
  DdsFrameStream(std::shared_ptr<DdsFrameLinks> links, std::string write_topic, std::string read_topic);
  std::shared_ptr<DdsFrameLinks> links_;  // the participant outlives the stream's entities
  std::string write_topic_, read_topic_;
  std::shared_ptr<State> state_;
};

}  // namespace symb::io
