// MedeaTask: mEDEA (medea.hpp; controller-models.md 6.3) running on one robot of a swarm, the
// third of issue 7's on-board evolution tasks. No explicit fitness: genomes spread by being heard.
// It drives the pure algorithm with time and a radio, and swaps whole controller TASKS as the
// one_plus_one task does: for each lifetime it removes the running controller and creates a new
// task of type `mlp` through the node's registry, the genome as its `weights`, hooked in:
//
//   ir --> controller(genome of this lifetime) --> wheels
//   MedeaTask --[genome text]--> radio --)))  ((( radio --[genome text, {sender}]--> MedeaTask
//
// The radio is any task named `radio` that transmits the bytes it is sent and sends on the bytes
// it receives, with the sender's index as the message's first number (sim::RadioTask over a
// sim::LocalRadio in simulation; a real transceiver's stream task on a robot).
//
// Every tick (the task's period: the broadcast period, 300 ms by default) an active robot sends
// its genome as text (evo::to_text, an io::Bytes blob made once per lifetime). Every received
// text goes to Medea::receive_text (malformed ones are counted and ignored). At the end of a
// lifetime (`lifetime`, default 12 s = 400 control steps of 30 ms, roborobo's gEvaluationTime)
// the algorithm picks the next genome; an inactive robot has NO controller (the wheels' watchdog
// stops them), does not broadcast, and keeps listening.
//
// Parameters (make time): lifetime, inputs, layers, activation (the mlp's; the genome length is
// its genome size), lo, hi, sigma, sigma_min, sigma_max, sigma_probability, controller, sensor,
// actuator, radio (task names). Randomness from the task's own stream (Task::random()).
// Probes at the end of every lifetime: "active" (0 or 1), "heard" (genomes in the list when it
// ended), "sigma". If a task it needs is missing it logs a warning once and retries every tick;
// if a controller cannot be created it logs the error and stops (state kFailed).
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "symb/evo/medea/medea.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::evo {

struct MedeaTaskOptions {
  MedeaOptions algorithm;
  kernel::Duration lifetime = std::chrono::seconds(12);
  std::string controller_type = "mlp";
  std::string controller = "controller";
  std::string controller_params = "inputs=7 layers=2 activation=tanh";
  std::string sensor = "ir", actuator = "wheels", radio = "radio";
};

class MedeaTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<MedeaTask>> create(MedeaTaskOptions options);

  // Safe from any thread. (EvolutionState: one_plus_one_task.hpp.)
  EvolutionState state() const;
  std::string error() const;
  bool active() const;
  RealGenome genome() const;  // the genome of the current (or last active) lifetime
  MedeaCounts counts() const;
  std::uint64_t controllers_created() const;
  std::uint64_t broadcasts() const;

 protected:
  void on_start() override;
  void on_tick() override;
  void on_message(const os::Message& m) override;

 private:
  explicit MedeaTask(MedeaTaskOptions options) : options_(std::move(options)) {}
  bool set_up();
  void start_lifetime();
  void fail(const std::string& why);
  void publish();

  MedeaTaskOptions options_;
  std::optional<Medea> algorithm_;
  os::TaskId sensor_, actuator_, radio_, controller_;
  bool have_controller_ = false;
  bool warned_missing_ = false;
  bool warned_malformed_ = false;
  kernel::Time lifetime_start_{0};
  os::Payload genome_message_;  // this lifetime's genome text, shared by every broadcast

  mutable std::mutex mu_;  // what the getters read
  EvolutionState state_ = EvolutionState::kWaiting;
  std::string error_;
  bool active_ = true;
  RealGenome genome_;
  MedeaCounts counts_;
  std::uint64_t created_ = 0;
  std::uint64_t broadcasts_ = 0;
};

// Registers the task type `medea` (defaults: priority 1, period 300 ms, queue 64).
kernel::Status register_medea_task_types(os::TaskTypeRegistry& registry);

}  // namespace symb::evo
