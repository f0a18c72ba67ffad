// The stop request a run checks between steps (SIGINT, SIGTERM; runner.hpp).
#pragma once

namespace dem {

// SIGINT and SIGTERM only set a flag (async-signal-safe); runs stop at the end of the current
// step. Installed by `dem run`; elsewhere the flag is never set.
void install_stop_handlers();
// 0 when no stop was requested, else the signal's number.
int stop_signal();

}  // namespace dem
