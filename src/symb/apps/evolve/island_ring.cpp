#include "symb/apps/evolve/island_ring.hpp"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <thread>

namespace symb::apps::evolve {
namespace {
constexpr int kReportTag = 15;
constexpr int kAliveTag = 16;
constexpr int kFiguresTag = 17;
constexpr int kNoticeTag = 18;
// A migrant's tag is its exchange's number (mod kTagSpan; MPI allows tags up to 32767 at least),
// so a migrant re-sent late, or sent by a new neighbour, is matched to the right exchange.
constexpr int kMigrantTagBase = 100;
constexpr std::uint64_t kTagSpan = 30000;
constexpr std::size_t kMaxGenes = 32;  // one message's inline numbers (os::Payload)
constexpr std::uint64_t kNever = IslandRing::kNever;
constexpr std::uint64_t kLeft = kNever - 1;  // found_at of a rank that left on its own (alive)
// A migrant on the wire: [gene count, fitness, genes..., zero padding].
using MigrantBuffer = std::array<double, 2 + kMaxGenes>;
// A notice to every rank: [rank, first exchange the ring skips it, exchange it was found missing
// at, or -1: it left on its own, its run failed].
using Notice = std::array<long long, 3>;
using Figures = IslandFigures;

int migrant_tag(std::uint64_t exchange) { return kMigrantTagBase + static_cast<int>(exchange % kTagSpan); }

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void pause_briefly() { std::this_thread::sleep_for(std::chrono::microseconds(200)); }

}  // namespace

class IslandRing::State {
 public:
  State(int rank, int size, double wait_seconds, const CliContext& ctx)
      : rank_(rank),
        size_(size),
        wait_(wait_seconds),
        beat_every_(std::min(1.0, wait_seconds / 4)),
        ctx_(ctx),
        gone_from_(size, kNever),
        found_at_(size, kNever),
        last_heard_(size, now_seconds()) {}

  // "Alive" to every rank still in the ring, at most every beat_every_.
  void beat() {
    const double now = now_seconds();
    if (now - last_beat_ < beat_every_) return;
    last_beat_ = now;
    for (int q = 0; q < size_; ++q) {
      if (q == rank_ || gone_from_[q] != kNever) continue;
      MPI_Request request = MPI_REQUEST_NULL;
      // The word never changes, so the request can go at once (MPI finishes the send on its own).
      if (MPI_Isend(&kAliveWord, 1, MPI_INT, q, kAliveTag, MPI_COMM_WORLD, &request) == MPI_SUCCESS)
        MPI_Request_free(&request);
    }
  }

  std::vector<float> exchange(const std::vector<float>& champion, double fitness) {
    const std::uint64_t k = exchange_++;
    drain();
    MigrantBuffer& out = sent_.emplace_back();
    const std::size_t n = std::min(champion.size(), kMaxGenes);
    out[0] = static_cast<double>(n);
    out[1] = fitness;
    for (std::size_t i = 0; i < n; ++i) out[2 + i] = champion[i];
    // A rank the others took as gone (silent too long) carries on alone: nobody sends to it any more.
    if (gone_from_[rank_] <= k) {
      sent_to_.push_back(rank_);
      return {};
    }
    const int to = next_at(k);
    sent_to_.push_back(to);
    if (to != rank_) send(out.data(), out.size(), MPI_DOUBLE, to, migrant_tag(k));

    MigrantBuffer got{};
    int from = previous_at(k);
    while (from != rank_) {
      MPI_Request request = MPI_REQUEST_NULL;
      if (MPI_Irecv(got.data(), static_cast<int>(got.size()), MPI_DOUBLE, from, migrant_tag(k), MPI_COMM_WORLD,
                    &request) != MPI_SUCCESS) {
        lose(from, k);
        return {};
      }
      double since = now_seconds();
      for (;;) {
        int done = 0;
        const bool failed = MPI_Test(&request, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS;
        if (done && !failed) {
          last_heard_[from] = now_seconds();
          const auto count = static_cast<std::size_t>(std::clamp(got[0], 0.0, static_cast<double>(kMaxGenes)));
          std::vector<float> migrant(count);
          for (std::size_t i = 0; i < count; ++i) migrant[i] = static_cast<float>(got[2 + i]);
          return migrant;
        }
        // A notice means a rank just waited for a gone one: whoever this rank waits for may be
        // held up behind it, so the wait starts again.
        beat();
        if (drain()) since = now_seconds();
        const bool silent = now_seconds() - std::max(since, last_heard_[from]) > wait_;
        if (failed || gone_from_[from] <= k || gone_from_[rank_] <= k || silent) {
          cancel(request);
          if (gone_from_[rank_] <= k) return {};
          // Another rank found it gone first: this exchange's migrant comes from the one before.
          if (!failed && gone_from_[from] <= k) break;
          lose(from, k);
          return {};
        }
        pause_briefly();
      }
      from = previous_at(k);
    }
    return {};
  }

  // This rank stops before the end (its run failed): the others stop waiting for it.
  void leave() { mark_gone(rank_, exchange_, kLeft, true); }

  // Every island's figures to every rank: the report's writer is the lowest rank still there,
  // whichever that is. Returns the figures heard (this rank's own included) if this rank writes
  // the report, else nothing.
  std::optional<std::vector<std::optional<Figures>>> gather(const Figures& mine) {
    std::vector<std::optional<Figures>> all(static_cast<std::size_t>(size_));
    all[static_cast<std::size_t>(rank_)] = mine;
    figures_out_ = mine;
    for (int r = 0; r < size_; ++r)
      if (r != rank_) send(figures_out_.data(), figures_out_.size(), MPI_DOUBLE, r, kFiguresTag);
    // Figures still to come from r: from every rank not gone, and from one that left on its own
    // (its run failed), which sends them right after saying so; its notice may be read first.
    const auto expected = [&](int r) {
      return !all[static_cast<std::size_t>(r)] && (gone_from_[r] == kNever || found_at_[r] == kLeft);
    };
    const auto heard_all = [&] {
      for (int r = 0; r < size_; ++r)
        if (expected(r)) return false;
      return true;
    };
    // Every rank listens until all the others finished (or are gone): a rank found gone late may
    // still need a migrant re-sent to its successor. Silent for `wait`: gone.
    double since = now_seconds();
    const auto waiting_for_someone = [&] {
      for (int r = 0; r < size_; ++r)
        if (expected(r) && now_seconds() - std::max(since, last_heard_[r]) <= wait_) return true;
      return false;
    };
    while (!heard_all() && waiting_for_someone()) {
      int waiting = 0;
      MPI_Status status;
      if (MPI_Iprobe(MPI_ANY_SOURCE, kFiguresTag, MPI_COMM_WORLD, &waiting, &status) == MPI_SUCCESS && waiting) {
        Figures f{};
        if (MPI_Recv(f.data(), static_cast<int>(f.size()), MPI_DOUBLE, status.MPI_SOURCE, kFiguresTag, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE) == MPI_SUCCESS)
          all[static_cast<std::size_t>(status.MPI_SOURCE)] = f;
        continue;
      }
      beat();
      if (drain()) since = now_seconds();
      pause_briefly();
    }
    // The first rank still there writes the report.
    for (int r = 0; r < rank_; ++r)
      if (all[static_cast<std::size_t>(r)]) {
        writer_ = r;
        return std::nullopt;
      }
    for (int r = 0; r < size_; ++r)
      if (!all[static_cast<std::size_t>(r)] && gone_from_[r] == kNever) mark_gone(r, exchange_, exchange_, false);
    return all;
  }

  // The report is written: the others may go. Under plain mpirun the first rank to exit with a
  // failure stops the job, so none leaves before the report is on disk.
  void report_written() {
    for (int q = 0; q < size_; ++q)
      if (q != rank_ && (gone_from_[q] == kNever || found_at_[q] == kLeft))
        send(&kAliveWord, 1, MPI_INT, q, kReportTag);
  }
  // Waits for the report's writer (the first rank it heard figures from) to say it is written, as
  // long as the writer is not silent for `wait`.
  void await_report() {
    const double since = now_seconds();
    for (;;) {
      int waiting = 0;
      MPI_Status status;
      if (MPI_Iprobe(MPI_ANY_SOURCE, kReportTag, MPI_COMM_WORLD, &waiting, &status) == MPI_SUCCESS && waiting) {
        int word = 0;
        MPI_Recv(&word, 1, MPI_INT, status.MPI_SOURCE, kReportTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        return;
      }
      beat();
      drain();
      if (writer_ < 0 || now_seconds() - std::max(since, last_heard_[writer_]) > wait_) return;
      pause_briefly();
    }
  }

  // Whether a peer is gone (or this rank was taken as gone): then MPI_Finalize is not safe.
  bool lost_any() const {
    for (int r = 0; r < size_; ++r)
      if (gone_from_[r] != kNever && found_at_[r] != kLeft) return true;
    return false;
  }
  // The sends that reached live peers are done (a healthy run's end, before MPI_Finalize).
  void finish_sends() {
    if (!requests_.empty()) MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    requests_.clear();
  }
  std::uint64_t gone_from(int r) const { return gone_from_[static_cast<std::size_t>(r)]; }
  std::uint64_t found_at(int r) const { return found_at_[static_cast<std::size_t>(r)]; }
  std::uint64_t missing() const { return missing_; }

 private:
  int next_at(std::uint64_t k) const {
    for (int step = 1; step < size_; ++step) {
      const int r = (rank_ + step) % size_;
      if (gone_from_[r] > k) return r;
    }
    return rank_;
  }
  int previous_at(std::uint64_t k) const {
    for (int step = 1; step < size_; ++step) {
      const int r = (rank_ + size_ - step) % size_;
      if (gone_from_[r] > k) return r;
    }
    return rank_;
  }

  // Buffers stay where they are until the send is done: deques of them, never shrunk.
  void send(const void* data, std::size_t count, MPI_Datatype type, int to, int tag) {
    MPI_Request request = MPI_REQUEST_NULL;
    if (MPI_Isend(data, static_cast<int>(count), type, to, tag, MPI_COMM_WORLD, &request) == MPI_SUCCESS)
      requests_.push_back(request);
  }
  static void cancel(MPI_Request& request) {
    if (request == MPI_REQUEST_NULL) return;
    MPI_Cancel(&request);
    MPI_Request_free(&request);
  }

  // The migrant of exchange k from `from` did not come: it is gone from the next exchange on.
  void lose(int from, std::uint64_t k) {
    ++missing_;
    ctx_.err << "symb evolve --islands: rank " << rank_ << ": no migrant from rank " << from << " for exchange "
             << k + 1 << ", and not a word from it for " << fixed(wait_, 1) << " s (--migrant-wait): rank " << from
             << " is taken as gone; the ring skips it from exchange " << k + 2 << "\n"
             << std::flush;
    mark_gone(from, k + 1, k, true);
  }

  void mark_gone(int r, std::uint64_t from_exchange, std::uint64_t found, bool tell) {
    if (gone_from_[r] <= from_exchange) return;
    gone_from_[r] = from_exchange;
    found_at_[r] = found;
    if (tell) {
      Notice& notice = notices_out_.emplace_back(
          Notice{r, static_cast<long long>(from_exchange), found == kLeft ? -1LL : static_cast<long long>(found)});
      for (int q = 0; q < size_; ++q)
        if (q != rank_) send(notice.data(), notice.size(), MPI_LONG_LONG, q, kNoticeTag);
    }
    // Migrants already sent to it for those exchanges go to the new neighbour.
    for (std::uint64_t m = from_exchange; m < sent_to_.size(); ++m) {
      if (sent_to_[m] != r) continue;
      sent_to_[m] = next_at(m);
      if (sent_to_[m] != rank_ && gone_from_[rank_] > m)
        send(sent_[m].data(), sent_[m].size(), MPI_DOUBLE, sent_to_[m], migrant_tag(m));
    }
  }

  // Takes the "alive" words and the notices that came; whether a notice came.
  bool drain() {
    for (;;) {
      int waiting = 0;
      MPI_Status status;
      if (MPI_Iprobe(MPI_ANY_SOURCE, kAliveTag, MPI_COMM_WORLD, &waiting, &status) != MPI_SUCCESS || !waiting) break;
      int word = 0;
      if (MPI_Recv(&word, 1, MPI_INT, status.MPI_SOURCE, kAliveTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE) != MPI_SUCCESS)
        break;
      last_heard_[status.MPI_SOURCE] = now_seconds();
    }
    bool any = false;
    for (;;) {
      int waiting = 0;
      MPI_Status status;
      if (MPI_Iprobe(MPI_ANY_SOURCE, kNoticeTag, MPI_COMM_WORLD, &waiting, &status) != MPI_SUCCESS || !waiting)
        return any;
      Notice n{};
      if (MPI_Recv(n.data(), static_cast<int>(n.size()), MPI_LONG_LONG, status.MPI_SOURCE, kNoticeTag, MPI_COMM_WORLD,
                   MPI_STATUS_IGNORE) != MPI_SUCCESS)
        return any;
      any = true;
      if (n[0] >= 0 && n[0] < size_ && n[1] >= 0 && n[2] >= -1)
        mark_gone(static_cast<int>(n[0]), static_cast<std::uint64_t>(n[1]),
                  n[2] < 0 ? kLeft : static_cast<std::uint64_t>(n[2]), false);
    }
  }

  static constexpr int kAliveWord = 1;

  int rank_, size_;
  double wait_, beat_every_;
  double last_beat_ = 0;
  const CliContext& ctx_;
  std::uint64_t exchange_ = 0;            // exchanges so far
  std::vector<std::uint64_t> gone_from_;  // per rank: the first exchange the ring skips it
  std::vector<std::uint64_t> found_at_;   // per rank: the exchange its migrant was found missing
  std::vector<double> last_heard_;        // per rank: when it last said anything
  int writer_ = -1;                       // the rank that writes the report, if not this one
  std::deque<MigrantBuffer> sent_;        // by exchange
  std::vector<int> sent_to_;              // by exchange
  std::deque<Notice> notices_out_;
  Figures figures_out_{};
  std::vector<MPI_Request> requests_;
  std::uint64_t missing_ = 0;
};

MpiSession::MpiSession() {
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) MPI_Init(nullptr, nullptr);
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  if (finalize_) MPI_Finalize();
}

IslandRing::IslandRing(int rank, int size, double wait_seconds, const CliContext& ctx)
    : state_(std::make_unique<State>(rank, size, wait_seconds, ctx)) {}
IslandRing::~IslandRing() = default;
void IslandRing::beat() { state_->beat(); }
std::vector<float> IslandRing::exchange(const std::vector<float>& champion, double fitness) {
  return state_->exchange(champion, fitness);
}
void IslandRing::leave() { state_->leave(); }
std::optional<std::vector<std::optional<IslandFigures>>> IslandRing::gather(const IslandFigures& mine) {
  return state_->gather(mine);
}
void IslandRing::report_written() { state_->report_written(); }
void IslandRing::await_report() { state_->await_report(); }
bool IslandRing::lost_any() const { return state_->lost_any(); }
void IslandRing::finish_sends() { state_->finish_sends(); }
std::uint64_t IslandRing::gone_from(int r) const { return state_->gone_from(r); }
std::uint64_t IslandRing::found_at(int r) const { return state_->found_at(r); }
std::uint64_t IslandRing::missing() const { return state_->missing(); }

}  // namespace symb::apps::evolve
