// The run harness: one loop for every phase (phase.hpp) with, once, the stability guard (one
// policy: the overlap every step; finiteness and the energy budget every kCheckEvery steps),
// the last good state, the stop signal, checkpoint cadence, progress and the clock.
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include "run/blowup.hpp"
#include "run/last_good.hpp"
#include "run/phase.hpp"
#include "run/recorder.hpp"
#include "run/status.hpp"
#include "run/thread_choice.hpp"

namespace dem {

class World;
struct SceneSpec;

// Finiteness and energy are checked every kCheckEvery steps (a scan of the disc arrays and a
// sum over the contacts: too costly every step); a NaN stops the run that many steps later at most.
constexpr long kCheckEvery = 10;

// What the guard carries from phase to phase (and in checkpoints).
struct Guard {
  double overlap_limit = 0;  // [cm] end.max_overlap x r_min at the phase's start
  EnergyWatch energy;        // budget from the phase's start (blowup.hpp)
};

// Where a run's loop spends its wall time (this process's part of the run): the time step itself
// (forces, contact lists, moves), the stability checks, the phase's own measures, the records
// (thermo rows, snapshots), checkpoints, and the rest of the loop (progress line, stop requests).
struct LoopTimes {
  double step = 0, checks = 0, measures = 0, records = 0, checkpoints = 0, total = 0;
  // Lines for run.log: each part in seconds and as a share of the loop.
  std::string text() const;
};

class Runner {
 public:
  explicit Runner(const SceneSpec& spec) : spec_(spec) {}

  // Drives `phase` to its end, a stop request or instability; `fresh`: from its begin, else
  // from a checkpoint restored with the world. The phase's finish runs in every case.
  Status run(Phase& phase, World& w, bool fresh);

  bool progress = false;
  Recorder record;           // thermo.csv and the periodic snapshots (recorder.hpp)
  long checkpoint_every = 0;                          // [steps] 0: none (multiples of the world's steps)
  std::function<void(const Phase&)> write_checkpoint; // called at that cadence and on a stop

  LastGood last_good;        // kept every kKeepEvery steps after a check passed
  ThreadChoice thread_choice;  // the threads each step runs with (integrator.thread_choice)
  Guard guard;
  double wall_seconds = 0;   // [s] of stepping, every phase and every process of the run
  LoopTimes loop;            // this process's loop, by part (run.log's timing breakdown)
  std::string reason;        // why the run is unstable

  // The wall time so far, this process's current phase included.
  double wall_now() const;

 private:
  std::string check(World& w, const Phase& phase);  // "" or why the run cannot be trusted
  const SceneSpec& spec_;
  double run_start_ = 0;     // wall_seconds when the current phase's loop started
  bool running_ = false;
  bool choice_started_ = false;
  std::chrono::steady_clock::time_point phase_start_;
};

}  // namespace dem
