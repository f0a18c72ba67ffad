// Running a scene to its end condition: rest (the paper's note 3), end time, or instability.
#pragma once

#include <string>

#include "run/blowup.hpp"
#include "run/control.hpp"
#include "physics/discs.hpp"
#include "run/last_good.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace dem {

enum class RunStatus { rest, end_time, unstable, interrupted };

struct RunResult {
  RunStatus status = RunStatus::end_time;
  std::string reason;          // why an unstable run stopped
  bool rest_reached = false;
  double rest_time = 0;        // [s] simulated time when rest was first detected
  double rest_threshold = 0;   // rest_factor * g dt^2 [cm]
  double mean_abs_du = 0, mean_abs_dv = 0;  // last measured (x and y increments per step)
  double wall_seconds = 0;
  LastGood last_good;          // state at the last check kept (written when unstable)
  bool energy_started = false; // the energy budget of blowup.hpp, set at the first step
  EnergyWatch energy;
};

const char* to_string(RunStatus s);

// Steps the world until its end condition. Progress goes to stderr when `progress`. The last
// good state goes to keep_file ("" : kept in memory).
RunResult run_scene(const SceneSpec& spec, World& w, bool progress, const std::string& keep_file = "");

// The same from the state in `res` (a fresh RunResult, or one restored from a checkpoint with
// the world): checkpoints through ctl (may be null), and a stop request (control.hpp) ends the
// run after the current step with status `interrupted`.
void continue_scene(const SceneSpec& spec, World& w, bool progress, RunResult& res, const RunControl* ctl);

}  // namespace dem
