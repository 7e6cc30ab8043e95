// Fuzzes the task-graph genome text (src/symb/evo/embryogenesis/task_graph_genome.hpp): any text must give a
// genome or an error "LINE:COLUMN: message", never a crash or a hang. An accepted genome must
// survive to_text exactly; its mutants must too; and checking it against a node (which runs every
// named type's factory on the parameters) must answer without changing the node.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>

#include "symb/control/control_task_types.hpp"
#include "symb/evo/embryogenesis/embryogenesis.hpp"
#include "symb/evo/embryogenesis/task_graph_genome.hpp"
#include "symb/evo/evo_task_types.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "located_error.hpp"

using symb::fuzz::located;
using namespace symb;

namespace {

struct Bench {
  kernel::VirtualTimeExecutor executor;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  Bench() {
    control::ControlResources resources;
    resources.read_program = [](std::string_view) -> kernel::Result<std::string> {
      return kernel::Error{"no files while fuzzing"};
    };
    if (!control::register_control_task_types(registry, resources)) std::abort();
    if (!evo::register_evo_task_types(registry, resources)) std::abort();
    node = std::make_unique<os::Node>(executor, os::NodeConfig{.name = "fuzz", .types = &registry});
  }
};

void round_trip(const evo::TaskGraphGenome& g) {
  const std::string printed = evo::to_text(g);
  auto again = evo::parse_task_graph(printed);
  if (!again || !(*again == g) || evo::to_text(*again) != printed) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Bench bench;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto r = evo::parse_task_graph(text);
  if (!r) {
    if (!located(r.error())) std::abort();
    return 0;
  }
  round_trip(*r);
  if (r->tasks.size() <= 8) {
    (void)evo::check_development(*r, *bench.node);
    if (bench.node->task_count() != 0) std::abort();
  }
  kernel::RandomStream random(size);
  evo::TaskGraphGenome m = *r;
  evo::GraphMutationOptions options;
  options.addable_types = {"fitness", "arbiter", "mlp"};
  for (int i = 0; i < 4; ++i) {
    evo::mutate(m, bench.registry, random, options);
    round_trip(m);
  }
  return 0;
}
