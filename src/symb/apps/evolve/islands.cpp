#include "symb/apps/evolve/islands.hpp"

#include <mpi.h>

#include <array>
#include <sstream>

#include "symb/apps/text_file.hpp"

namespace symb::apps::evolve {
namespace {

constexpr int kMigrantTag = 19;
constexpr std::size_t kMaxGenes = 32;  // one message's inline numbers (os::Payload)
// A migrant on the wire: [gene count, fitness, genes..., zero padding].
using MigrantBuffer = std::array<double, 2 + kMaxGenes>;

// MPI's life in this process: from the first call to the last, once.
class MpiSession {
 public:
  MpiSession() {
    int ready = 0;
    MPI_Initialized(&ready);
    if (!ready) MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiSession() { MPI_Finalize(); }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  int rank_ = 0, size_ = 1;
};

// The figures rank 0 reports for every island.
struct IslandFigures {
  double seed = 0, evaluations = 0, migrants = 0, champion_fitness = 0, hash_hi = 0, hash_lo = 0;
};

}  // namespace

int run_islands(EvolveOptions options, const IslandOptions& islands, const CliContext& ctx) {
  MpiSession mpi;
  const int rank = mpi.rank(), size = mpi.size();
  const std::filesystem::path out = options.out_dir;
  options.out_dir = out / ("island_" + std::to_string(rank));
  options.seed = islands.base_seed + static_cast<std::uint64_t>(rank);
  if (rank != 0) options.on_progress = {};
  if (size > 1 && islands.every.count() > 0) {
    options.migrate_every = islands.every;
    const int next = (rank + 1) % size, previous = (rank + size - 1) % size;
    options.migrate = [next, previous](const std::vector<float>& champion, double fitness) {
      MigrantBuffer send{}, got{};
      const std::size_t n = std::min(champion.size(), kMaxGenes);
      send[0] = static_cast<double>(n);
      send[1] = fitness;
      for (std::size_t i = 0; i < n; ++i) send[2 + i] = champion[i];
      MPI_Sendrecv(send.data(), static_cast<int>(send.size()), MPI_DOUBLE, next, kMigrantTag, got.data(),
                   static_cast<int>(got.size()), MPI_DOUBLE, previous, kMigrantTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      const auto count = static_cast<std::size_t>(std::min(got[0], static_cast<double>(kMaxGenes)));
      std::vector<float> migrant(count);
      for (std::size_t i = 0; i < count; ++i) migrant[i] = static_cast<float>(got[2 + i]);
      return migrant;
    };
  }
  auto result = run_evolution(options);
  // Every rank reaches the gather, a failed one with its error flagged, so rank 0 can say which.
  IslandFigures mine;
  std::string error;
  if (result) {
    mine = {static_cast<double>(result->seed),
            static_cast<double>(result->evaluations),
            static_cast<double>(result->migrants),
            result->champion_fitness,
            static_cast<double>(result->history_hash >> 32),
            static_cast<double>(result->history_hash & 0xFFFFFFFFu)};
  } else {
    error = result.error();
    mine.seed = -1;
    ctx.err << "symb evolve --islands: rank " << rank << ": " << error << "\n";
  }
  std::vector<IslandFigures> all(static_cast<std::size_t>(size));
  MPI_Gather(&mine, 6, MPI_DOUBLE, all.data(), 6, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (rank != 0) return result ? kExitOk : kExitFailure;

  std::ostringstream text;
  text << "islands: " << size << " ranks, migration every "
       << (islands.every.count() > 0 && size > 1 ? fixed(std::chrono::duration<double>(islands.every).count(), 0) + " s"
                                                 : std::string("never"))
       << " (ring), base seed " << islands.base_seed << "\n"
       << "island  seed  evaluations  migrants  champion_fitness  history_hash\n";
  bool failed = false;
  int best = -1;
  std::uint64_t combined = 1469598103934665603ull;
  for (int r = 0; r < size; ++r) {
    const IslandFigures& f = all[static_cast<std::size_t>(r)];
    if (f.seed < 0) {
      text << r << "  failed\n";
      failed = true;
      continue;
    }
    const std::uint64_t hash = (static_cast<std::uint64_t>(f.hash_hi) << 32) | static_cast<std::uint64_t>(f.hash_lo);
    combined = (combined ^ hash) * 1099511628211ull;
    text << r << "  " << static_cast<std::uint64_t>(f.seed) << "  " << static_cast<std::uint64_t>(f.evaluations) << "  "
         << static_cast<std::uint64_t>(f.migrants) << "  " << fixed(f.champion_fitness, 6) << "  " << hex64(hash)
         << "\n";
    if (best < 0 || f.champion_fitness > all[static_cast<std::size_t>(best)].champion_fitness) best = r;
  }
  if (best >= 0)
    text << "best island: " << best << ", champion fitness "
         << fixed(all[static_cast<std::size_t>(best)].champion_fitness, 6) << " ("
         << (out / ("island_" + std::to_string(best)) / "champion.genome").string() << ")\n";
  double mean = 0;
  for (const IslandFigures& f : all) mean += f.champion_fitness / size;
  text << "mean champion fitness: " << fixed(mean, 6) << "\n"
       << "islands hash: " << hex64(combined) << "\n";
  if (auto st = write_file(out / "islands.txt", text.str()); !st) {
    ctx.err << "symb evolve --islands: " << st.error() << "\n";
    return kExitFailure;
  }
  if (!islands.quiet) ctx.out << text.str() << "results in " << out.string() << "/\n" << std::flush;
  return failed ? kExitFailure : kExitOk;
}

}  // namespace symb::apps::evolve
