// DeviceThreads: who calls a Sensor's or an Actuator's methods, which says whether its data needs
// a lock. Most drivers are fed from a thread of their own (a serial reader, an interrupt), and under
// the thread executor a task and the shell may use one device at once: kAny, the default, locks.
// A simulated robot whose world and node run on one non-concurrent executor (virtual-time,
// lockstep) has every call made from that executor's contexts, one at a time, with a happens-before
// between them (the lockstep executor's windows): kOneAtATime skips the lock. The lock is worth
// skipping there: its locked instruction also waits for every load in flight, and a swarm's robots
// took 5 % (10,000 robots, their state from memory) to 9 % (100) less CPU without it.
// A device made kOneAtATime must not be called from any other thread (a shell command reaches it
// as injected work, on the executor's context).
#pragma once

#include <cstdint>

namespace symb::robot {

enum class DeviceThreads : std::uint8_t { kAny, kOneAtATime };

}  // namespace symb::robot
