#include "run/fill_phase.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/world.hpp"
#include "run/runner.hpp"
#include "scene/scene.hpp"

namespace dem {

void FillPhase::attach(World& w) {
  rest.threshold = spec_.rest_factor * std::hypot(w.gx, w.gy) * w.dt * w.dt;  // note 3: ~1e-9 cm at dt = 1e-4
  max_steps_ = static_cast<long>(std::ceil(spec_.end_time / w.dt - 1e-9));
}

Status FillPhase::begin(World& w, std::string&) { return w.steps < max_steps_ ? Status::running : Status::end_time; }

void FillPhase::before_step(World& w, bool stopping) {
  // A fill ends on a step that recorded its pair forces (the contacts output): the last step,
  // a rest check (where rest is found), or, on a stop request, the next step.
  w.record_pair_forces = stopping || w.steps + 1 == max_steps_ ||
                         (spec_.stop_at_rest && !rest.reached && (w.steps + 1) % kCheckEvery == 0);
  w.measure_increments = (w.steps + 1) % kCheckEvery == 0;  // Verlet's rest measure
}

Status FillPhase::after_step(World& w) {
  if (w.steps % kCheckEvery == 0) {
    w.mean_abs_increment(rest.mean_abs_du, rest.mean_abs_dv);
    // Rest counts once no prescribed translation is still to come (a floor lowered later).
    if (rest.mean_abs_du < rest.threshold && rest.mean_abs_dv < rest.threshold && !rest.reached &&
        w.time >= w.moving.translations_end()) {
      rest.reached = true;
      rest.time = w.time;
      if (spec_.stop_at_rest) return Status::rest;
    }
  }
  return w.steps < max_steps_ ? Status::running : Status::end_time;
}

void FillPhase::finish(World& w, Status) {
  w.record_pair_forces = w.measure_increments = false;  // what follows (a discharge) asks for its own
}

std::string FillPhase::progress(const World& w) const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "fill t = %.4f / %.4f s  step %ld  mean|du| %.2e (rest < %.2e)", w.time,
                spec_.end_time, w.steps, std::max(rest.mean_abs_du, rest.mean_abs_dv), rest.threshold);
  return buf;
}

double FillPhase::fraction(const World& w) const { return max_steps_ > 0 ? double(w.steps) / max_steps_ : 1.0; }

}  // namespace dem
