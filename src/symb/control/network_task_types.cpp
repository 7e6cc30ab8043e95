#include "symb/control/network_task_types.hpp"

namespace symb::control {

// Being written (issue 5): no types yet.
kernel::Status register_network_task_types(os::TaskTypeRegistry& /*registry*/, const ControlResources& /*resources*/) {
  return {};
}

}  // namespace symb::control
