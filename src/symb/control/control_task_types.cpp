#include "symb/control/control_task_types.hpp"

#include "symb/control/ahhs/ahhs_task_types.hpp"
#include "symb/control/cpg/cpg_task_types.hpp"
#include "symb/control/mdl2e/mdl2e_task_types.hpp"
#include "symb/control/network/network_task_types.hpp"
#include "symb/control/organism/organism_task_types.hpp"
#include "symb/control/schemas/schema_task_types.hpp"
#include "symb/control/snn/snn_task_types.hpp"
#include "symb/control/subsumption/subsumption_task_types.hpp"
#include "symb/kernel/source_text.hpp"

namespace symb::control {

std::string shown_reference(std::string_view reference) { return kernel::shortened(reference, 120); }

kernel::Status register_control_task_types(os::TaskTypeRegistry& registry, ControlResources resources) {
  if (auto st = register_mdl2e_task_types(registry, resources); !st) return st;
  if (auto st = register_ahhs_task_types(registry, resources); !st) return st;
  if (auto st = register_network_task_types(registry, resources); !st) return st;
  if (auto st = register_subsumption_task_types(registry, resources); !st) return st;
  if (auto st = register_schema_task_types(registry, resources); !st) return st;
  if (auto st = register_cpg_task_types(registry, resources); !st) return st;
  if (auto st = register_organism_task_types(registry, resources); !st) return st;
  return register_snn_task_types(registry, resources);
}

}  // namespace symb::control
