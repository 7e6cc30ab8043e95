#include "symb/apps/evolve/islands.hpp"

#include <mpi.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <limits>
#include <sstream>
#include <string_view>
#include <thread>

#include "symb/apps/text_file.hpp"

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
constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();
constexpr std::uint64_t kLeft = kNever - 1;  // found_at of a rank that left on its own (alive)
// A migrant on the wire: [gene count, fitness, genes..., zero padding].
using MigrantBuffer = std::array<double, 2 + kMaxGenes>;
// A notice to every rank: [rank, first exchange the ring skips it, exchange it was found missing
// at, or -1: it left on its own, its run failed].
using Notice = std::array<long long, 3>;
// What the report's writer hears from every island: seed, evaluations, migrants, migrants taken,
// champion fitness, history hash (two halves), migrants missing, 1 if the run finished.
using Figures = std::array<double, 9>;

int migrant_tag(std::uint64_t exchange) { return kMigrantTagBase + static_cast<int>(exchange % kTagSpan); }

// MPI's life in this process: from the first call to the last, once. Errors are returned, not
// fatal, so a peer that is gone is this program's to handle.
class MpiSession {
 public:
  MpiSession() {
    int ready = 0;
    MPI_Initialized(&ready);
    if (!ready) MPI_Init(nullptr, nullptr);
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  // MPI_Finalize synchronises with every process: with one gone it may wait for ever (measured
  // with OpenMPI 4.1.4), so an island that lost a peer leaves without it, its files written.
  ~MpiSession() {
    if (finalize_) MPI_Finalize();
  }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  void skip_finalize() { finalize_ = false; }

 private:
  int rank_ = 0, size_ = 1;
  bool finalize_ = true;
};

double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void pause_briefly() { std::this_thread::sleep_for(std::chrono::microseconds(200)); }

// One rank's view of the ring: who is gone and from which exchange the ring skips them, and the
// migrants it sent (re-sent to the new neighbour when it learns late that the addressee is gone).
// Every rank says it is alive to the others about once a second (beat(): from the run's progress
// and from every wait), so a slow rank is told from a dead one. A migrant whose sender has been
// silent for `wait` of wall clock is counted missing; its sender is then taken as gone from the
// next exchange on, and every rank is told, so its predecessor sends to its successor from then
// on. Which exchange that is depends on when the rank died; given it, every migrant is the one a
// rank sent at that exchange, whenever it arrives.
class Ring {
 public:
  Ring(int rank, int size, double wait_seconds, const CliContext& ctx)
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
    const auto heard_all = [&] {
      for (int r = 0; r < size_; ++r)
        if (!all[static_cast<std::size_t>(r)] && gone_from_[r] == kNever) return false;
      return true;
    };
    // Every rank listens until all the others finished (or are gone): a rank found gone late may
    // still need a migrant re-sent to its successor. Silent for `wait`: gone.
    double since = now_seconds();
    const auto waiting_for_someone = [&] {
      for (int r = 0; r < size_; ++r)
        if (!all[static_cast<std::size_t>(r)] && gone_from_[r] == kNever &&
            now_seconds() - std::max(since, last_heard_[r]) <= wait_)
          return true;
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

std::string exchange_time(std::uint64_t exchange, kernel::Duration every) {
  return fixed(std::chrono::duration<double>(every).count() * static_cast<double>(exchange + 1) / 60.0, 1) + " min";
}

}  // namespace

int run_islands(EvolveOptions options, const IslandOptions& islands, const CliContext& ctx) {
  MpiSession mpi;
  const int rank = mpi.rank(), size = mpi.size();
  const std::filesystem::path out = options.out_dir;
  options.out_dir = out / ("island_" + std::to_string(rank));
  options.seed = islands.base_seed + static_cast<std::uint64_t>(rank);
  const double wait = std::chrono::duration<double>(islands.wait).count();
  if (rank == 0 && size > 1 && !islands.quiet && std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr) {
    const char* recovery = std::getenv("OMPI_MCA_orte_enable_recovery");
    if (recovery == nullptr || std::string_view(recovery) != "1")
      ctx.err << "symb evolve --islands: without `mpirun --enable-recovery`, a rank that dies stops every island\n"
              << std::flush;
  }
  Ring ring(rank, size, wait, ctx);
  if (size > 1) {
    // The run's progress (every 100 ms of wall clock) carries the "alive" beat; rank 0 shows it.
    auto show = rank == 0 ? options.on_progress : std::function<void(const EvolveProgress&)>{};
    options.on_progress = [&ring, show](const EvolveProgress& p) {
      if (show) show(p);
      ring.beat();
    };
  }
  if (size > 1 && islands.every.count() > 0) {
    options.migrate_every = islands.every;
    options.migrate = [&ring](const std::vector<float>& champion, double fitness) {
      return ring.exchange(champion, fitness);
    };
  }
  auto result = run_evolution(options);
  Figures mine{};
  mine[0] = static_cast<double>(options.seed.value_or(0));
  mine[7] = static_cast<double>(ring.missing());
  if (result) {
    mine[1] = static_cast<double>(result->evaluations);
    mine[2] = static_cast<double>(result->migrants);
    mine[3] = static_cast<double>(result->migrants_taken);
    mine[4] = result->champion_fitness;
    mine[5] = static_cast<double>(result->history_hash >> 32);
    mine[6] = static_cast<double>(result->history_hash & 0xFFFFFFFFu);
    mine[8] = 1;
  } else {
    ctx.err << "symb evolve --islands: rank " << rank << ": " << result.error() << "\n" << std::flush;
    if (size > 1) ring.leave();
  }
  const auto all = size > 1 ? ring.gather(mine) : std::optional(std::vector<std::optional<Figures>>{mine});
  const int own_status = result ? kExitOk : kExitFailure;
  const auto leave = [&](int status) {
    if (ring.lost_any()) {
      mpi.skip_finalize();
    } else {
      ring.finish_sends();
    }
    return status;
  };
  if (!all) {
    ring.await_report();
    return leave(own_status);
  }

  std::ostringstream text;
  const bool migrating = islands.every.count() > 0 && size > 1;
  text << "islands: " << size << " ranks, migration every "
       << (migrating ? fixed(std::chrono::duration<double>(islands.every).count(), 0) + " s" : std::string("never"))
       << " (ring), base seed " << islands.base_seed << "\n"
       << "island  seed  evaluations  migrants  taken  champion_fitness  history_hash\n";
  int best = -1, reported = 0;
  std::vector<int> gone, failed;
  double sum = 0;
  std::uint64_t combined = 1469598103934665603ull;
  for (int r = 0; r < size; ++r) {
    const std::optional<Figures>& f = (*all)[static_cast<std::size_t>(r)];
    const std::string folder = "island_" + std::to_string(r) + "/";
    if (!f) {
      gone.push_back(r);
      text << r << "  " << islands.base_seed + static_cast<std::uint64_t>(r) << "  gone: ";
      if (ring.found_at(r) < ring.gone_from(r) && migrating && ring.gone_from(r) != kNever)
        text << "its migrant for exchange " << ring.found_at(r) + 1 << " (at "
             << exchange_time(ring.found_at(r), islands.every) << ") never came; the ring skipped it from exchange "
             << ring.gone_from(r) + 1;
      else
        text << "no figures at the end";
      text << "; " << folder << " keeps what it wrote\n";
      continue;
    }
    const Figures& v = *f;
    if (v[8] != 1) {
      failed.push_back(r);
      text << r << "  " << static_cast<std::uint64_t>(v[0]) << "  failed (its error is on its rank's stderr)\n";
      continue;
    }
    const std::uint64_t hash = (static_cast<std::uint64_t>(v[5]) << 32) | static_cast<std::uint64_t>(v[6]);
    combined = (combined ^ hash) * 1099511628211ull;
    text << r << "  " << static_cast<std::uint64_t>(v[0]) << "  " << static_cast<std::uint64_t>(v[1]) << "  "
         << static_cast<std::uint64_t>(v[2]) << "  " << static_cast<std::uint64_t>(v[3]) << "  " << fixed(v[4], 6)
         << "  " << hex64(hash);
    if (v[7] > 0) text << "  (migrants missing: " << static_cast<std::uint64_t>(v[7]) << ")";
    if (ring.gone_from(r) != kNever)
      text << "  (taken as gone from exchange " << ring.gone_from(r) + 1 << ": silent too long; it ran on alone)";
    text << "\n";
    sum += v[4];
    ++reported;
    if (best < 0 || v[4] > (*(*all)[static_cast<std::size_t>(best)])[4]) best = r;
  }
  if (best >= 0)
    text << "best island: " << best << ", champion fitness " << fixed((*(*all)[static_cast<std::size_t>(best)])[4], 6)
         << " (" << (out / ("island_" + std::to_string(best)) / "champion.genome").string() << ")\n";
  text << "mean champion fitness: " << fixed(reported > 0 ? sum / reported : 0, 6) << "\n"
       << "islands hash: " << hex64(combined) << "\n";
  const auto list = [](const std::vector<int>& ranks) {
    std::string s;
    for (int r : ranks) s += (s.empty() ? "" : ", ") + std::to_string(r);
    return s;
  };
  if (!gone.empty())
    text << "gone: island " << list(gone) << " (killed, or silent for --migrant-wait " << fixed(wait, 1)
         << " s); the others finished and are above\n";
  if (!failed.empty()) text << "failed: island " << list(failed) << "\n";
  if (rank != 0) text << "written by rank " << rank << ": the ranks below it are gone\n";
  const auto written = write_file(out / "islands.txt", text.str());
  if (size > 1) ring.report_written();
  if (!written) {
    ctx.err << "symb evolve --islands: " << written.error() << "\n";
    return leave(kExitFailure);
  }
  if (!gone.empty())
    ctx.err << "symb evolve --islands: island " << list(gone) << " gone; the other " << reported << " finished: see "
            << (out / "islands.txt").string() << "\n"
            << std::flush;
  if (!islands.quiet) ctx.out << text.str() << "results in " << out.string() << "/\n" << std::flush;
  return leave(gone.empty() && failed.empty() ? own_status : kExitFailure);
}

}  // namespace symb::apps::evolve
