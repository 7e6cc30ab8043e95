#include "symb/io/dds/dds_frame_stream.hpp"

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include <dds/dds.h>

#include "symb/io/dds/dds_participant.hpp"

#include "FrameChunk.h"

namespace symb::io {

namespace {
constexpr int kChunkBatch = 16;
}

const char* to_string(DdsPeerState s) {
  switch (s) {
    case DdsPeerState::kWaiting: return "waiting";
    case DdsPeerState::kAlive: return "alive";
    case DdsPeerState::kLost: return "lost (no liveliness within the lease)";
    case DdsPeerState::kLeft: return "left";
  }
  return "?";
}

struct DdsFrameLinks::Core {
  dds::Participant participant;
};

struct DdsFrameStream::State {
  mutable std::mutex mu;
  std::condition_variable cv;
  std::deque<std::byte> in;
  DdsPeerState peer = DdsPeerState::kWaiting;
  bool closed = false;
  std::uint32_t alive = 0;
  DdsFrameStreamCounts counts;
  dds_entity_t read_topic = 0, write_topic = 0, reader = 0, writer = 0;
};

namespace {

void on_chunks(dds_entity_t reader, void* arg) {
  auto& s = *static_cast<DdsFrameStream::State*>(arg);
  void* samples[kChunkBatch];
  dds_sample_info_t infos[kChunkBatch];
  bool any = false;
  for (;;) {
    samples[0] = nullptr;
    const int n = dds_take(reader, samples, infos, kChunkBatch, kChunkBatch);
    if (n <= 0) break;
    {
      std::lock_guard lock(s.mu);
      for (int i = 0; i < n; ++i) {
        if (!infos[i].valid_data) continue;
        const auto& c = *static_cast<const symb_msg_dds__FrameChunk_*>(samples[i]);
        const auto* b = reinterpret_cast<const std::byte*>(c.data._buffer);
        s.in.insert(s.in.end(), b, b + c.data._length);
        ++s.counts.chunks_read;
        s.counts.bytes_read += c.data._length;
        any = true;
      }
    }
    dds_return_loan(reader, samples, n);
  }
  if (any) s.cv.notify_all();
}

void on_peer_liveliness(dds_entity_t, const dds_liveliness_changed_status_t status, void* arg) {
  auto& s = *static_cast<DdsFrameStream::State*>(arg);
  {
    std::lock_guard lock(s.mu);
    s.alive = status.alive_count;
    if (status.not_alive_count_change > 0) {  // the lease ran out: killed, hung or cut off
      s.counts.peers_lost += static_cast<std::uint64_t>(status.not_alive_count_change);
      if (status.alive_count == 0) s.peer = DdsPeerState::kLost;
    } else if (status.alive_count_change < 0) {  // its writer was deleted: a clean end
      ++s.counts.peers_left;
      if (status.alive_count == 0 && s.peer != DdsPeerState::kLost) s.peer = DdsPeerState::kLeft;
    }
    // Any live writer is a peer: one that comes after another left (a foreign writer, a restarted
    // process) opens the stream again, as a serial line's device that comes back does.
    if (status.alive_count > 0) s.peer = DdsPeerState::kAlive;
  }
  s.cv.notify_all();
}

}  // namespace

DdsFrameLinks::DdsFrameLinks(DdsFrameOptions options) : options_(std::move(options)), core_(std::make_unique<Core>()) {}

DdsFrameLinks::~DdsFrameLinks() { dds::close_participant(core_->participant); }

kernel::Result<std::shared_ptr<DdsFrameLinks>> DdsFrameLinks::create(DdsFrameOptions options) {
  if (options.prefix.empty()) return kernel::Error{"dds frames: empty topic prefix"};
  std::shared_ptr<DdsFrameLinks> links(new DdsFrameLinks(std::move(options)));
  auto p = dds::open_participant(links->options_.domain, links->options_.lease, "dds frames");
  if (!p) return kernel::Error{p.error()};
  links->core_->participant = *p;
  return links;
}

std::string DdsFrameLinks::topic(std::string_view channel, std::string_view direction) const {
  return "rt/" + dds::topic_part(options_.prefix) + "/" + dds::topic_part(channel) + "/" + dds::topic_part(direction);
}

kernel::Result<std::shared_ptr<DdsFrameStream>> DdsFrameLinks::stream(std::string_view channel, std::string_view out,
                                                                      std::string_view in) {
  std::shared_ptr<DdsFrameStream> s(new DdsFrameStream(shared_from_this(), topic(channel, out), topic(channel, in)));
  DdsFrameStream::State& st = *s->state_;
  const dds_entity_t p = core_->participant.participant;
  const auto fail = [&](const std::string& what, dds_return_t rc) -> kernel::Result<std::shared_ptr<DdsFrameStream>> {
    return kernel::Error{"dds frames: " + what + ": " + dds::error_text(rc)};
  };
  st.write_topic = dds_create_topic(p, &symb_msg_dds__FrameChunk__desc, s->write_topic_.c_str(), nullptr, nullptr);
  if (st.write_topic < 0) return fail("topic " + s->write_topic_, st.write_topic);
  st.read_topic = dds_create_topic(p, &symb_msg_dds__FrameChunk__desc, s->read_topic_.c_str(), nullptr, nullptr);
  if (st.read_topic < 0) return fail("topic " + s->read_topic_, st.read_topic);
  dds_qos_t* qos = dds::reliable_qos(options_.lease);
  dds_listener_t* l = dds_create_listener(&st);
  dds_lset_data_available(l, on_chunks);
  dds_lset_liveliness_changed(l, on_peer_liveliness);
  const dds_entity_t reader = dds_create_reader(p, st.read_topic, qos, l);
  dds_delete_listener(l);
  const dds_entity_t writer = reader < 0 ? reader : dds_create_writer(p, st.write_topic, qos, nullptr);
  dds_delete_qos(qos);
  if (reader < 0) return fail("reader of " + s->read_topic_, reader);
  {
    std::lock_guard lock(st.mu);
    st.reader = reader;
  }
  if (writer < 0) return fail("writer of " + s->write_topic_, writer);
  std::lock_guard lock(st.mu);
  st.writer = writer;
  return s;
}

DdsFrameStream::DdsFrameStream(std::shared_ptr<DdsFrameLinks> links, std::string write_topic, std::string read_topic)
    : Device("dds:" + read_topic),
      IOStream(""),
      links_(std::move(links)),
      write_topic_(std::move(write_topic)),
      read_topic_(std::move(read_topic)),
      state_(std::make_shared<State>()) {}

DdsFrameStream::~DdsFrameStream() {
  // Deleting the reader waits for its running listeners, which hold a pointer to the state.
  for (dds_entity_t e : {state_->writer, state_->reader, state_->write_topic, state_->read_topic})
    if (e > 0) dds_delete(e);
}

kernel::Status DdsFrameStream::open() {
  std::lock_guard lock(state_->mu);
  if (state_->closed) return kernel::Error{name() + ": closed (" + to_string(state_->peer) + ")"};
  return {};
}

void DdsFrameStream::close() {
  {
    std::lock_guard lock(state_->mu);
    state_->closed = true;
  }
  state_->cv.notify_all();
}

bool DdsFrameStream::is_open() const {
  std::lock_guard lock(state_->mu);
  return !state_->closed && state_->peer != DdsPeerState::kLost && state_->peer != DdsPeerState::kLeft;
}

kernel::Result<std::size_t> DdsFrameStream::read_some(std::span<std::byte> buf, kernel::Duration timeout) {
  State& s = *state_;
  std::unique_lock lock(s.mu);
  const auto gone = [&] { return s.peer == DdsPeerState::kLost || s.peer == DdsPeerState::kLeft; };
  s.cv.wait_for(lock, timeout, [&] { return !s.in.empty() || gone() || s.closed; });
  if (!s.in.empty()) {
    const std::size_t n = std::min(buf.size(), s.in.size());
    std::copy_n(s.in.begin(), n, buf.begin());
    s.in.erase(s.in.begin(), s.in.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
  }
  if (s.closed) return kernel::Error{name() + ": closed"};
  if (gone()) return kernel::Error{std::string("the peer on ") + read_topic_ + " " + to_string(s.peer)};
  return std::size_t{0};
}

kernel::Status DdsFrameStream::write_all(std::span<const std::byte> data) {
  dds_entity_t writer = 0;
  {
    std::lock_guard lock(state_->mu);
    if (state_->closed) return kernel::Error{name() + ": closed"};
    writer = state_->writer;
  }
  if (writer <= 0) return kernel::Error{write_topic_ + ": this end finished sending"};
  symb_msg_dds__FrameChunk_ c{};
  c.data._length = c.data._maximum = static_cast<std::uint32_t>(data.size());
  c.data._buffer = reinterpret_cast<std::uint8_t*>(const_cast<std::byte*>(data.data()));
  c.data._release = false;
  const dds_return_t rc = dds_write(writer, &c);
  std::lock_guard lock(state_->mu);
  if (rc != DDS_RETCODE_OK) {
    ++state_->counts.write_errors;
    return kernel::Error{write_topic_ + ": " + dds::error_text(rc)};
  }
  ++state_->counts.chunks_written;
  state_->counts.bytes_written += data.size();
  return {};
}

DdsPeerState DdsFrameStream::peer() const {
  std::lock_guard lock(state_->mu);
  return state_->peer;
}

bool DdsFrameStream::wait_matched(kernel::Duration timeout) const {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    dds_entity_t reader = 0, writer = 0;
    {
      std::lock_guard lock(state_->mu);
      reader = state_->reader;
      writer = state_->writer;
    }
    dds_publication_matched_status_t pm{};
    dds_subscription_matched_status_t sm{};
    const bool w = writer > 0 && dds_get_publication_matched_status(writer, &pm) >= 0 && pm.current_count > 0;
    const bool r = dds_get_subscription_matched_status(reader, &sm) >= 0 && sm.current_count > 0;
    if (w && r) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

bool DdsFrameStream::flush(kernel::Duration timeout) const {
  dds_entity_t writer = 0;
  {
    std::lock_guard lock(state_->mu);
    writer = state_->writer;
  }
  if (writer <= 0) return true;
  return dds_wait_for_acks(writer, std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count()) ==
         DDS_RETCODE_OK;
}

void DdsFrameStream::finish_sending() {
  dds_entity_t writer = 0;
  {
    std::lock_guard lock(state_->mu);
    std::swap(writer, state_->writer);
  }
  if (writer > 0) dds_delete(writer);
}

DdsFrameStreamCounts DdsFrameStream::counts() const {
  std::lock_guard lock(state_->mu);
  return state_->counts;
}

}  // namespace symb::io
