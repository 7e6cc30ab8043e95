// One AHHS compartment as its own task, and the mixer that gathers actuators into one command.
// The paper (section IV): "each compartment can be calculated by a separate task and the hooking
// mechanism can supply each compartment task with sensor values and it can also handle the
// hormone exchange among compartments (diffusion)". Every compartment task holds the whole
// network description and steps only its own compartment; together they give, step for step,
// the levels the whole-network task gives (ahhs_task.hpp).
//
//   ir --port 0--> compartment k --port 1 (levels)--> neighbours' compartment tasks
//                               --port 2 (actuators)--> ahhs_mixer --port 0--> wheels
//
// The exchange protocol (a plain message, so a bridge can carry it across nodes):
//  - port 1: [compartment id, h0, ..., h(H-1)]: the sender's local levels of this step (after its
//    own rules, before diffusion). A receiver uses it when the id is one of its neighbours and
//    ignores every other id (so one bridge may broadcast everything it carries).
//  - port 2: [actuator index, value, index, value, ...]: the compartment's actuators, in [-1, 1].
// A step: a sensor vector (port 0) runs the local update, sends port 1 and port 2, and waits for
// one level message from every neighbour; when all are there, it diffuses and the step is done.
// Level messages are kept per neighbour in arrival order (a carrier must keep one sender's
// messages in order), at most kMaxHeldLevels each (the oldest goes). If the next sensor vector
// comes before every neighbour answered, the step is finished with the neighbours that did, the
// missing ones counted in `missed_exchanges` (a detached robot must not stall the rest).
#pragma once

#include <deque>

#include "symb/control/ahhs/ahhs_task.hpp"

namespace symb::control {

inline constexpr os::Port kAhhsLevelsPort = 1;
inline constexpr os::Port kAhhsActuatorPairsPort = 2;
inline constexpr std::size_t kMaxHeldLevels = 4;

struct AhhsCompartmentStats {
  std::uint64_t steps = 0;             // local updates
  std::uint64_t exchanges = 0;         // steps finished with every neighbour's levels
  std::uint64_t missed_exchanges = 0;  // neighbour levels missing when a step had to finish
  std::uint64_t foreign_levels = 0;    // level messages of compartments that are not neighbours
  std::uint64_t ignored = 0;           // malformed messages
};

class AhhsCompartmentTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<AhhsCompartmentTask>> create(ahhs::Network network, std::uint32_t compartment,
                                                                     AhhsTaskOptions options = {});
  std::uint32_t compartment() const { return compartment_; }
  // Safe from any thread: the levels after the last finished step.
  std::vector<float> levels() const;
  AhhsCompartmentStats stats() const;

 protected:
  void on_message(const os::Message& m) override;

 private:
  AhhsCompartmentTask(ahhs::Model model, std::uint32_t compartment, AhhsTaskOptions options);
  void ignore(const std::string& why);
  void finish_step(bool forced);
  void try_finish();

  ahhs::Model model_;  // the description; its own state is unused
  std::uint32_t compartment_;
  AhhsTaskOptions options_;
  std::vector<std::uint32_t> neighbours_;
  std::vector<std::deque<std::vector<float>>> held_;  // per neighbour, in neighbours_ order
  std::vector<float> row_, local_, sensors_, actuators_, message_;
  std::vector<const float*> rows_;
  bool awaiting_ = false;
  os::WarningLimiter warning_;
  mutable std::mutex mu_;  // shown_
  std::vector<float> shown_;
  struct Counters {  // kernel/counter.hpp
    kernel::Counter steps, exchanges, missed_exchanges, foreign_levels, ignored;
    AhhsCompartmentStats snapshot() const {
      return {.steps = steps.load(),
              .exchanges = exchanges.load(),
              .missed_exchanges = missed_exchanges.load(),
              .foreign_levels = foreign_levels.load(),
              .ignored = ignored.load()};
    }
  } counters_;
};

// Gathers [index, value] pairs from compartment tasks and sends the whole actuator vector, scaled,
// once every index has a value for this round. An index that comes again before the round is
// complete flushes the round (missing actuators keep their last value).
class AhhsMixerTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<AhhsMixerTask>> create(std::size_t actuators, AhhsTaskOptions options = {});
  std::vector<float> last() const;  // the last vector sent, unscaled
  std::uint64_t sent() const;
  std::uint64_t flushed() const;  // rounds sent incomplete

 protected:
  void on_message(const os::Message& m) override;

 private:
  AhhsMixerTask(std::size_t actuators, AhhsTaskOptions options);
  void flush();

  AhhsTaskOptions options_;
  std::vector<float> values_;
  std::vector<bool> have_;
  std::size_t have_count_ = 0;
  std::vector<float> out_;
  os::WarningLimiter warning_;
  mutable std::mutex mu_;  // last_
  std::vector<float> last_;
  kernel::Counter sent_, flushed_;
};

}  // namespace symb::control
