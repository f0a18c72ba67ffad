#include "run/scene_run.hpp"

#include <cstdio>

#include "io/binary.hpp"
#include "physics/world.hpp"
#include "scene/resolve.hpp"
#include "scene/scene.hpp"

namespace dem {

SceneRun::SceneRun(const SceneSpec& spec, World& w, const std::string& out) : runner(spec), fill(spec), spec_(spec), w_(w) {
  from_state_ = !spec.start_from.empty();
  if (!from_state_) phases_.push_back(&fill);
  if (spec.discharge.enabled) {
    discharge = std::make_unique<DischargePhase>(spec, out);
    phases_.push_back(discharge.get());
  }
  if (spec.shear_box.shear) {  // paper 2
    shear = std::make_unique<ShearPhase>(spec, out);
    phases_.push_back(shear.get());
  }
  // Beside the outputs for large worlds, in memory for small ones (last_good.hpp).
  runner.last_good.set_file(out.empty() || w.discs.size() < kLastGoodInFileFrom ? "" : out + "/last_good.bin");
  runner.record.configure(spec, out, w.dt);
  if (discharge) discharge->record = &runner.record;
  if (shear) shear->record = &runner.record;
}

void SceneRun::set_checkpoints(long every_steps, const std::string& path, const CheckpointKey& key) {
  ckpt_path_ = path;
  key_ = key;
  runner.checkpoint_every = every_steps;
  runner.write_checkpoint = [this](const Phase& p) { checkpoint(p); };
}

void SceneRun::checkpoint(const Phase& current) {
  write_checkpoint(ckpt_path_, key_, w_, runner, fill.rest, current.name(), &current == &fill ? nullptr : &current);
}

void SceneRun::resume(const std::string& path, const CheckpointKey& key) {
  std::string phase;
  read_checkpoint(path, key, w_, runner, fill.rest, phase, [&](const std::string& name, BinaryIn& r) {
    for (std::size_t k = 0; k < phases_.size(); ++k)
      if (name == phases_[k]->name()) {
        current_ = k;
        if (phases_[k] != &fill) phases_[k]->load(r);
        if (phases_[k] == discharge.get())
          for (std::size_t i = 0; i < w_.discs.size(); ++i)
            if (const int id = w_.discs.id_at(i); id < 0 || static_cast<std::uint64_t>(id) >= discharge->at_open().size())
              r.fail("corrupt checkpoint (disc ids)");
        return;
      }
    r.fail("written in a phase (" + name + ") this scene does not have");
  });
  fresh_ = false;
  if (discharge && phases_[current_] == discharge.get())
    if (const std::string why = discharge->series_file_problem(); !why.empty()) throw std::runtime_error(why);
}

const char* SceneRun::phase_name() const { return current_ < phases_.size() ? phases_[current_]->name() : "end"; }

namespace {
// The scene as the engine resolved it (dem resolve: every value with its default), one table a
// line, the discs counted rather than listed: run.log's echo of its input.
std::string resolved_echo(const SceneSpec& s, std::size_t n_discs) {
  nlohmann::json j = resolved_scene_json(s);  // s.discs may be released once the world holds them
  std::string out = "  resolved scene (dem resolve; its " + std::to_string(n_discs) + " discs not listed):\n";
  j.erase("discs");
  for (auto it = j.begin(); it != j.end(); ++it) out += "    " + it.key() + " = " + it.value().dump() + "\n";
  return out;
}
}  // namespace

Status SceneRun::run(bool progress, bool print) {
  runner.progress = progress;
  if (fresh_ && current_ == 0) runner.last_good.keep(w_.discs, w_.time);
  if (log && fresh_ && current_ == 0) log->file_only(resolved_echo(spec_, w_.discs.size()));
  for (; current_ < phases_.size(); ++current_, fresh_ = true) {
    Phase& p = *phases_[current_];
    if ((print || log) && fresh_ && &p != &fill) {
      // A state file does not say whether its run reached rest: not reported as "NOT at rest".
      const char* settled = from_state_ ? "from the state file" : fill.rest.reached ? "at rest" : "NOT at rest";
      char line[160];
      if (&p == discharge.get()) std::snprintf(line, sizeof line, "  opening the slit at t = %.4f s (fill %s)\n", w_.time, settled);
      else std::snprintf(line, sizeof line, "  shearing from t = %.4f s (compression %s)\n", w_.time, settled);
      if (log) {
        log->add(line);
      } else {
        std::fputs(line, stdout);
        std::fflush(stdout);
      }
    }
    status = runner.run(p, w_, fresh_);
    if (status == Status::interrupted && runner.write_checkpoint) checkpoint(p);
    if (status == Status::unstable || status == Status::interrupted) break;
  }
  if (phases_.empty()) status = Status::end_time;  // a state file and nothing to run
  runner.record.write();
  if (log) log->file_only(runner.loop.text());
  if (discharge) discharge->at_open().discard();  // a checkpoint carries its own copy
  return status;
}

RunSummary SceneRun::summary(nlohmann::ordered_json& extra) {
  RunSummary s;
  s.status = to_string(status);
  s.unstable = status == Status::unstable;
  if (s.unstable) s.reason = runner.reason;
  s.rest_reached = fill.rest.reached;
  s.rest_time = fill.rest.time;
  s.rest_threshold = fill.rest.threshold;
  s.mean_abs_du = fill.rest.mean_abs_du;
  s.mean_abs_dv = fill.rest.mean_abs_dv;
  s.wall_seconds = runner.wall_seconds;
  const ThreadChoice& tc = runner.thread_choice;
  extra["thread_choice"] = {{"mode", tc.enabled() ? "auto" : "off"}, {"probes", tc.probes},
                            {"steps_one_thread", tc.steps_at[0]}, {"steps_threads", tc.steps_at[1]}};
  if (s.unstable && runner.last_good.has()) {
    good_ = runner.last_good.load();
    s.good = &good_;
  }
  // The discharge's or shear's entries, when the run got to it.
  const Phase* last = current_ < phases_.size() ? phases_[current_] : (phases_.empty() ? nullptr : phases_.back());
  if (last && last != &fill) {
    extra["status"] = s.status;
    if (s.unstable) extra["reason"] = s.reason;
    extra[last->name()] = last->metrics();
  }
  return s;
}

void SceneRun::discard_kept() { runner.last_good.discard(); }

Status run_fill(const SceneSpec& spec, World& w, Rest* rest) {
  Runner runner(spec);
  FillPhase fill(spec);
  runner.last_good.keep(w.discs, w.time);
  const Status s = runner.run(fill, w, true);
  if (rest) *rest = fill.rest;
  return s;
}

}  // namespace dem
