// What a run checks between steps: a stop request (SIGINT, SIGTERM) and periodic checkpoints.
#pragma once

#include <functional>

namespace dem {

struct RunResult;
struct DischargeState;

// SIGINT and SIGTERM only set a flag (async-signal-safe); runs stop at the end of the current
// step. Installed by `dem run`; elsewhere the flag is never set.
void install_stop_handlers();
// 0 when no stop was requested, else the signal's number.
int stop_signal();

struct RunControl {
  long checkpoint_every = 0;  // [steps] 0: none; after every step whose count is a multiple
  std::function<void(const RunResult&)> fill_checkpoint;            // during the fill
  std::function<void(const DischargeState&)> discharge_checkpoint;  // during a discharge
};

}  // namespace dem
