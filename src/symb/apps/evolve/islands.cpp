#include "symb/apps/evolve/islands.hpp"

#include <chrono>
#include <cstdlib>
#include <sstream>
#include <string_view>

#include "symb/apps/evolve/island_ring.hpp"
#include "symb/apps/text_file.hpp"

namespace symb::apps::evolve {
namespace {

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
  IslandRing ring(rank, size, wait, ctx);
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
  IslandFigures mine{};
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
  const auto all = size > 1 ? ring.gather(mine) : std::optional(std::vector<std::optional<IslandFigures>>{mine});
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
    const std::optional<IslandFigures>& f = (*all)[static_cast<std::size_t>(r)];
    const std::string folder = "island_" + std::to_string(r) + "/";
    if (!f) {
      gone.push_back(r);
      text << r << "  " << islands.base_seed + static_cast<std::uint64_t>(r) << "  gone: ";
      if (ring.found_at(r) < ring.gone_from(r) && migrating && ring.gone_from(r) != IslandRing::kNever)
        text << "its migrant for exchange " << ring.found_at(r) + 1 << " (at "
             << exchange_time(ring.found_at(r), islands.every) << ") never came; the ring skipped it from exchange "
             << ring.gone_from(r) + 1;
      else
        text << "no figures at the end";
      text << "; " << folder << " keeps what it wrote\n";
      continue;
    }
    const IslandFigures& v = *f;
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
    if (ring.gone_from(r) != IslandRing::kNever)
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
