#include "run/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include <unistd.h>

#include "physics/world.hpp"
#include "run/control.hpp"
#include "scene/scene.hpp"

namespace dem {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double min_radius(const World& w) {
  double rmin = 1e300;
  for (std::size_t i = 0; i < w.discs.size(); ++i) rmin = std::min(rmin, w.discs.r(i));
  return rmin;
}

// What went wrong, for the message of an unstable run.
std::string diagnose(const World& w, double overlap_limit, const char* phase, const char* length) {
  const Discs& d = w.discs;
  std::ostringstream os;
  os.precision(6);
  for (std::size_t i = 0; i < d.size(); ++i)
    if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i]) || !std::isfinite(d.vx[i]) || !std::isfinite(d.vy[i]) ||
        !std::isfinite(d.omega[i])) {
      os << "non-finite state of disc " << d.id_at(i) << " at t = " << w.time << " s (step " << w.steps << ", "
         << phase << ")";
      return os.str();
    }
  os << "overlap " << w.max_overlap << ' ' << length << " exceeds the limit " << overlap_limit << ' ' << length
     << " (end.max_overlap x r_min) at t = "
     << w.time << " s (step " << w.steps << ", " << phase << "); kinetic energy " << w.kinetic_energy();
  return os.str();
}

std::string duration_text(double s) {
  char buf[32];
  if (!(s >= 0) || !std::isfinite(s)) return "?";
  if (s < 120) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 7200) std::snprintf(buf, sizeof buf, "%.0fmin", s / 60);
  else std::snprintf(buf, sizeof buf, "%.1fh", s / 3600);
  return buf;
}

}  // namespace

double Runner::wall_now() const { return running_ ? run_start_ + seconds_since(phase_start_) : wall_seconds; }

// Runs every step: the unit names go into the failure messages only, so they are looked up there.
std::string Runner::check(World& w, const Phase& phase) {
  if (!(w.max_overlap <= guard.overlap_limit)) {
    w.pay_kick();  // the diagnosis reads the velocities
    return diagnose(w, guard.overlap_limit, phase.name(), unit_names(spec_.units).length);
  }
  if (w.steps % kCheckEvery == 0) {
    if (!w.all_finite()) return diagnose(w, guard.overlap_limit, phase.name(), unit_names(spec_.units).length);
    if (std::string grew = guard.energy.check(w, spec_.units); !grew.empty()) return grew + " (" + phase.name() + ")";
    if (w.steps % kKeepEvery == 0) last_good.keep(w.discs, w.time);  // checked: finite, within budget
  }
  return "";
}

std::string LoopTimes::text() const {
  const double rest = std::max(0.0, total - step - checks - measures - records - checkpoints);
  const std::pair<const char*, double> parts[] = {
      {"time step (forces, contact lists, moves)", step}, {"checks (overlap, finiteness, energy)", checks},
      {"the phase's measures (rest, flow, walls)", measures}, {"records (thermo rows, snapshots)", records},
      {"checkpoints", checkpoints}, {"rest of the loop (progress, stop requests)", rest}};
  char head[96];
  std::snprintf(head, sizeof head, "  loop time by part, this process (%.3f s):\n", total);
  std::string out = head;
  for (const auto& [name, s] : parts) {
    char line[160];
    std::snprintf(line, sizeof line, "    %-44s %10.4f s %6.1f %%\n", name, s, total > 0 ? 100.0 * s / total : 0.0);
    out += line;
  }
  return out;
}

Status Runner::run(Phase& phase, World& w, bool fresh) {
  phase.attach(w);
  Status status = Status::running;
  if (fresh) {
    guard.overlap_limit = spec_.max_overlap_fraction * min_radius(w);
    status = phase.begin(w, reason);
    guard.energy.start(w, spec_.max_energy_gain);  // after begin: a discharge's budget starts with the gate open
    record.phase_start(w, phase.name());
  }
  if (!choice_started_) {  // once a run (its phases share the measurements)
    thread_choice.start(w, spec_.thread_choice);
    choice_started_ = true;
  }
  phase_start_ = Clock::now();
  run_start_ = wall_seconds;
  running_ = true;
  auto last_print = phase_start_;
  const double fraction0 = phase.fraction(w);
  const long steps0 = w.steps;
  bool printed = false, stopping = false;
  // On a terminal the line is redrawn in place; in a log (stderr not a terminal) a line is added.
  const bool terminal = isatty(fileno(stderr)) != 0;
  while (status == Status::running) {
    phase.before_step(w, stopping);
    if (record.snapshot_due(w.steps + 1)) w.record_pair_forces = true;  // the snapshot's contact totals
    const auto t_step = Clock::now();
    w.defer_closing_kick = phase.pays_own_kick();
    w.step();
    const auto t_stepped = Clock::now();
    const double stepped = std::chrono::duration<double>(t_stepped - t_step).count();
    loop.step += stepped;
    thread_choice.after_step(w, stepped);
    // Velocity Verlet's closing half kick is owed to the next step's first sweep (one pass over
    // the arrays instead of two) unless this step's checks, records or checkpoint read the
    // velocities.
    if (w.steps % kCheckEvery == 0 || record.due(w.steps) || (checkpoint_every > 0 && w.steps % checkpoint_every == 0))
      w.pay_kick();
    std::string why = check(w, phase);
    const auto t_checked = Clock::now();
    loop.checks += std::chrono::duration<double>(t_checked - t_stepped).count();
    if (!why.empty()) {
      reason = why;
      status = Status::unstable;
      break;
    }
    status = phase.after_step(w);
    const auto t_measured = Clock::now();
    loop.measures += std::chrono::duration<double>(t_measured - t_checked).count();
    if (status != Status::running) break;
    record.after_step(w, phase.name());  // before a stop: the step's row is in the checkpoint
    loop.records += seconds_since(t_measured);
    // A stop request ends the run on a step that recorded its pair forces (the contacts
    // output): this one, or the next, which before_step then asks to record.
    if (stop_signal()) stopping = true;
    if (stopping && w.pair_forces_current()) {
      status = Status::interrupted;
      break;
    }
    // Checkpoints follow the world's step count: a resumed run writes them at the same steps.
    if (checkpoint_every > 0 && w.steps % checkpoint_every == 0 && write_checkpoint) {
      const auto t_ckpt = Clock::now();
      phase.flush();
      write_checkpoint(phase);
      loop.checkpoints += seconds_since(t_ckpt);
    }
    if (progress && (w.steps & 1023) == 0) {
      const auto now = Clock::now();
      if (std::chrono::duration<double>(now - last_print).count() > spec_.progress_interval) {
        last_print = now;
        const double el = seconds_since(phase_start_), f = phase.fraction(w);
        const double eta = f > fraction0 ? el * (1 - f) / (f - fraction0) : NAN;
        std::fprintf(stderr, terminal ? "\r  %s  %.3g steps/s  %s elapsed, ETA %s   " : "  %s  %.3g steps/s  %s elapsed, ETA %s\n",
                     phase.progress(w).c_str(), (w.steps - steps0) / std::max(el, 1e-9), duration_text(el).c_str(),
                     duration_text(eta).c_str());
        std::fflush(stderr);
        printed = terminal;
      }
    }
  }
  if (printed) std::fprintf(stderr, "\n");
  w.pay_kick();  // what follows (the phase's end, its files, another phase) reads v(t)
  w.defer_closing_kick = false;
  wall_seconds = run_start_ + seconds_since(phase_start_);
  loop.total += seconds_since(phase_start_);
  running_ = false;
  phase.finish(w, status);
  record.phase_end(w, phase.name(), status);
  return status;
}

}  // namespace dem
