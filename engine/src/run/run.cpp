#include "run/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace dem {

const char* to_string(RunStatus s) {
  return s == RunStatus::rest ? "rest" : s == RunStatus::end_time ? "end_time"
         : s == RunStatus::unstable ? "unstable" : "interrupted";
}

namespace {
// Finds what went wrong, for the message of an unstable run.
std::string diagnose(const World& w, double overlap_limit) {
  const Discs& d = w.discs;
  std::ostringstream os;
  os.precision(6);
  for (std::size_t i = 0; i < d.size(); ++i)
    if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i]) || !std::isfinite(d.vx[i]) || !std::isfinite(d.vy[i]) ||
        !std::isfinite(d.omega[i])) {
      os << "non-finite state of disc " << d.id_at(i) << " at t = " << w.time << " s (step " << w.steps << ")";
      return os.str();
    }
  os << "overlap " << w.max_overlap << " cm exceeds the limit " << overlap_limit << " cm (end.max_overlap x r_min) at t = "
     << w.time << " s (step " << w.steps << "); kinetic energy " << w.kinetic_energy();
  return os.str();
}
}  // namespace

RunResult run_scene(const SceneSpec& spec, World& w, bool progress, const std::string& keep_file) {
  RunResult res;
  res.last_good.set_file(keep_file);
  res.last_good.keep(w.discs, w.time);
  continue_scene(spec, w, progress, res, nullptr);
  return res;
}

void continue_scene(const SceneSpec& spec, World& w, bool progress, RunResult& res, const RunControl* ctl) {
  res.status = RunStatus::end_time;
  res.reason.clear();
  const double g = std::hypot(w.gx, w.gy);
  res.rest_threshold = spec.rest_factor * g * w.dt * w.dt;  // note 3: ~1e-9 cm at dt = 1e-4
  double rmin = 1e300;
  for (std::size_t i = 0; i < w.discs.size(); ++i) rmin = std::min(rmin, w.discs.r(i));
  const double overlap_limit = spec.max_overlap_fraction * rmin;
  const long max_steps = static_cast<long>(std::ceil(spec.end_time / w.dt - 1e-9));
  const long check_every = 10;
  const double wall_before = res.wall_seconds;
  if (!res.energy_started) {
    res.energy.start(w, spec.max_energy_gain);
    res.energy_started = true;
  }

  const auto t0 = std::chrono::steady_clock::now();
  auto last_print = t0;
  // A run ends on a step that recorded its pair forces (the contacts output): the last step, a
  // check step when the run stops at rest (where rest is found), or, on a stop request, the step
  // after the request.
  bool stop_after = false;
  RunStatus stop_status = RunStatus::end_time;
  while (w.steps < max_steps) {
    w.record_pair_forces = stop_after || w.steps + 1 == max_steps ||
                           (spec.stop_at_rest && !res.rest_reached && (w.steps + 1) % check_every == 0);
    w.measure_increments = (w.steps + 1) % check_every == 0;  // Verlet's rest measure
    w.step();
    // A run that cannot be trusted stops here: overlap blow-up or non-finite values.
    if (!(w.max_overlap <= overlap_limit)) {
      res.status = RunStatus::unstable;
      res.reason = diagnose(w, overlap_limit);
      break;
    }
    if (w.steps % check_every == 0) {
      w.mean_abs_increment(res.mean_abs_du, res.mean_abs_dv);
      if (!std::isfinite(res.mean_abs_du) || !std::isfinite(res.mean_abs_dv)) {
        res.status = RunStatus::unstable;
        res.reason = diagnose(w, overlap_limit);
        break;
      }
      const std::string grew = res.energy.check(w);  // energy created: a blow-up on its way
      if (!grew.empty()) {
        res.status = RunStatus::unstable;
        res.reason = grew;
        break;
      }
      if (res.mean_abs_du < res.rest_threshold && res.mean_abs_dv < res.rest_threshold && !res.rest_reached) {
        res.rest_reached = true;
        res.rest_time = w.time;
        if (spec.stop_at_rest) {
          stop_after = true;
          stop_status = RunStatus::rest;
        }
      }
      if (w.steps % kKeepEvery == 0) res.last_good.keep(w.discs, w.time);
    }
    if (stop_signal() && !stop_after) {
      stop_after = true;
      stop_status = RunStatus::interrupted;
    }
    if (stop_after && w.pair_forces_current()) {
      res.status = stop_status;
      break;
    }
    if (ctl && ctl->checkpoint_every > 0 && w.steps % ctl->checkpoint_every == 0 && ctl->fill_checkpoint) {
      res.wall_seconds = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ctl->fill_checkpoint(res);
    }
    if (progress && (w.steps & 1023) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_print).count() > 2.0) {
        last_print = now;
        const double el = std::chrono::duration<double>(now - t0).count();
        std::fprintf(stderr, "\r  t = %.4f / %.4f s  step %ld  mean|du| %.2e (rest < %.2e)  %.1fs elapsed   ",
                     w.time, spec.end_time, w.steps, std::max(res.mean_abs_du, res.mean_abs_dv),
                     res.rest_threshold, el);
        std::fflush(stderr);
      }
    }
  }
  if (progress && std::chrono::duration<double>(last_print - t0).count() > 0) std::fprintf(stderr, "\n");
  w.record_pair_forces = w.measure_increments = false;  // what follows (a discharge) asks for its own
  res.wall_seconds = wall_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace dem
