// IslandRing: the ring that carries the island model's migrants between MPI ranks (`symb evolve
// --islands`, islands.hpp) and survives a rank that dies. OpenMPI 4.1 as Debian builds it has no
// fault-tolerance extension (ULFM): a send to a dead rank neither fails nor returns, so a dead rank
// is known only by its silence. Every rank says "alive" to the others about once a second (beat());
// a migrant whose sender has been silent for `wait` of wall clock is counted missing, its sender is
// taken as gone from the next exchange on, and every rank is told, so its predecessor sends to its
// successor from then on (migrants already sent to it are re-sent there). Given the exchange a rank
// was found gone at, every migrant is the one a rank sent at that exchange, whenever it arrives:
// with no rank gone the exchanges are those of a plain ring, and a run is deterministic.
//
// At the end every island's figures go to every rank (gather), and the lowest rank still there
// writes the report; the others wait until it is written (await_report), since under a plain
// mpirun the first rank to exit with a failure stops the job.
//
//   MpiSession mpi;                                   // MPI_Init .. MPI_Finalize
//   IslandRing ring(mpi.rank(), mpi.size(), 60.0, ctx);
//   auto migrant = ring.exchange(champion, fitness);  // at each migration instant
//   auto all = ring.gather(mine);                     // this rank writes the report if set
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::evolve {

// MPI's life in this process: from the first call to the last, once. Errors are returned, not
// fatal, so a peer that is gone is this program's to handle.
class MpiSession {
 public:
  MpiSession();
  // MPI_Finalize synchronises with every process: with one gone it may wait for ever (measured
  // with OpenMPI 4.1.4), so an island that lost a peer leaves without it, its files written.
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  void skip_finalize() { finalize_ = false; }

 private:
  int rank_ = 0, size_ = 1;
  bool finalize_ = true;
};

// What the report's writer hears from every island: seed, evaluations, migrants, migrants taken,
// champion fitness, history hash (two halves), migrants missing, 1 if the run finished.
using IslandFigures = std::array<double, 9>;

class IslandRing {
 public:
  // gone_from() of a rank the ring never skipped.
  static constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

  IslandRing(int rank, int size, double wait_seconds, const CliContext& ctx);
  ~IslandRing();
  IslandRing(const IslandRing&) = delete;
  IslandRing& operator=(const IslandRing&) = delete;

  // "Alive" to every rank still in the ring, at most about once a second.
  void beat();
  // The next exchange: this rank's champion to its successor, its predecessor's migrant back
  // (empty when none came: gone, or this rank alone).
  std::vector<float> exchange(const std::vector<float>& champion, double fitness);
  // This rank stops before the end (its run failed): the others stop waiting for it.
  void leave();
  // Every island's figures to every rank. Returns the figures heard (this rank's own included) if
  // this rank writes the report (the lowest rank still there), else nothing.
  std::optional<std::vector<std::optional<IslandFigures>>> gather(const IslandFigures& mine);
  // The report is written: the others may go.
  void report_written();
  // Waits for the report's writer to say it is written, as long as the writer is not silent.
  void await_report();
  // Whether a peer is gone (or this rank was taken as gone): then MPI_Finalize is not safe.
  bool lost_any() const;
  // The sends that reached live peers are done (a healthy run's end, before MPI_Finalize).
  void finish_sends();
  // Per rank: the first exchange the ring skips it (kNever: never), the exchange its migrant was
  // found missing at.
  std::uint64_t gone_from(int r) const;
  std::uint64_t found_at(int r) const;
  std::uint64_t missing() const;  // migrants this rank waited for in vain

 private:
  class State;  // MPI's requests and buffers: mpi.h stays out of this header
  std::unique_ptr<State> state_;
};

}  // namespace symb::apps::evolve
