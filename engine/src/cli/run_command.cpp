// dem run: parse -> load -> build -> run the phases -> write; with --engine CODE, the scene in
// a reference code (`python3 -m dem.compare.engine_run`, which gets the arguments untouched).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/cli.hpp"
#include "cli/picture_process.hpp"
#include "io/out_dir.hpp"
#include "io/outputs.hpp"
#include "io/run_log.hpp"
#include "io/state.hpp"
#include "measures/wall_loads.hpp"
#include "physics/free_heap.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"
#include "run/checkpoint.hpp"
#include "run/control.hpp"
#include "run/scene_run.hpp"
#include "scene/scene.hpp"

namespace dem::cli {

namespace {

const char* kRunFooter =
    "The engine writes data (docs/outputs.md); the pictures of a run (network.png, side_walls.png and\n"
    "a discharge's frames, wall ratios and flow) are drawn by " DEM_PYTHON_EXE " -m dem.compare.figures run DIR,\n"
    "or with the run by --pictures.\n"
    "The scene is validated completely before anything is written; a bad scene exits with 2 and\n"
    "leaves no output directory. A run that blows up (non-finite values, overlap beyond\n"
    "end.max_overlap x r_min) stops with 3 and writes the last good state. SIGINT or SIGTERM stops\n"
    "at the end of the current step, writes a checkpoint and all outputs (status \"interrupted\")\n"
    "and exits with 130 (SIGINT) or 143 (SIGTERM).";

// dem run's command line.
struct RunArgs {
  std::string scene, out, save_to, engine;
  SceneOverrides ov;
  bool quiet = false, resume = false, pictures = false;
  double checkpoint_every = -1;  // [s] -1: the scene's output.checkpoint_every
  std::string np, settle, timeout;  // --engine's own: handed on as given
};

void add_native_options(CLI::App& run, RunArgs& a) {
  const char* g = "Options of a run in this engine";
  run.add_option("--dt", a.ov.dt, "time step [s], overrides integrator.dt")->type_name("S")->check(number_above(0))->group(g);
  run.add_option("--scheme", a.ov.scheme,
                 "paper_eq18 | paper_eq19 | velocity_verlet | velocity_verlet_onset, overrides integrator.scheme")
      ->type_name("NAME")
      ->check(one_of({"paper_eq18", "paper_eq19", "velocity_verlet", "velocity_verlet_onset"}))
      ->group(g);
  run.add_option("--end-time", a.ov.end_time, "maximum simulated time [s], overrides end.time")
      ->type_name("S")->check(number_above(0))->group(g);
  run.add_flag("--force-dt", a.ov.force_dt, "run even if dt is above the computed stability bound")->group(g);
  run.add_option("--threads", a.ov.threads,
                 "threads of the force and integration loops (integrator.threads, default 1);\n"
                 "every N gives the bits of N = 1, the serial loop")
      ->type_name("N")->check(integer_in(1, kMaxThreads))->group(g);
  run.add_option("--from", a.ov.from, "start from a saved state (overrides start.from; skips the fill)")
      ->type_name("STATE")->group(g);
  run.add_option("--save-state", a.save_to, "save the final state (positions, velocities, forces, contact history)")
      ->type_name("FILE")->group(g);
  run.add_option("--checkpoint-every", a.checkpoint_every,
                 "write DIR/checkpoint.dem every S simulated seconds (overrides\n"
                 "output.checkpoint_every; 0: none)")
      ->type_name("S")->check(number_above(0, true))->group(g);
  run.add_flag("--resume", a.resume,
               "continue from DIR/checkpoint.dem (same scene file, engine and options);\n"
               "the result is bit-identical to a run never stopped")->group(g);
  run.add_flag("--no-vtu", a.ov.no_vtu, "no VTU files and no PVD indexes: the CSV files alone (output.vtu = \"none\")")
      ->group(g);
}

void add_engine_options(CLI::App& run, RunArgs& a) {
  const char* g = "Options of a run in a reference code";
  CLI::Option* engine =
      run.add_option("--engine", a.engine,
                     "run the scene in the real LIGGGHTS, LAMMPS or YADE (liggghts|lammps|yade) with the\n"
                     "shared law and write the same outputs (docs/compare.md, \"Running a scene in a\n"
                     "reference code\"); exit 2 when the code cannot express the scene (the field named)")
          ->type_name("CODE")->check(one_of({"liggghts", "lammps", "yade"}))->group(g);
  run.add_option("--np", a.np, "MPI ranks (liggghts, lammps: mpirun -np N) or yade -j N")
      ->type_name("N")->needs(engine)->group(g);
  run.add_option("--settle", a.settle, "the settling time [s] before a discharge opens")
      ->type_name("S")->needs(engine)->group(g);
  run.add_option("--timeout", a.timeout, "the wall-clock limit of the program [s] (exit 4)")
      ->type_name("S")->needs(engine)->group(g);
}

// The command that continues an interrupted run: this one's own arguments with --resume.
std::string resume_command(int argc, char** argv) {
  std::string cmd = shell_quote(g_program) + " run";
  for (int a = 0; a < argc; ++a)
    if (std::string(argv[a]) != "--resume") cmd += " " + shell_quote(argv[a]);
  return cmd + " --resume";
}

// The discharge's or shear's result line.
void print_phase_result(const SceneRun& run, RunLog& log) {
  if (run.discharge && run.discharge->outcome().status != Status::running) {
    const DischargeOutcome& o = run.discharge->outcome();
    log.say("  discharge: %s after %.3f s; %zu discs out (%d by 1 s), flow %.4g discs/s, %s; peak/static bottom %.2f, side %.2f\n",
            to_string(o.status), o.duration, o.removed, o.out_at_1s, o.flow_rate_discs, o.pattern.c_str(),
            o.peak_ratio_bottom, o.peak_ratio_side);
  }
  if (run.shear && run.shear->outcome().samples > 0) {
    const ShearOutcome& o = run.shear->outcome();
    log.say("  shear: %s to strain %.4f; peak tau/sigma %.4f at strain %.4f (windowed %.4f), sigma %.4g\n",
            to_string(run.status), o.strain_final, o.peak_ratio, o.strain_at_peak, o.peak_ratio_windowed,
            o.sigma_initial);
  }
}

// A scene loaded, its world built (and started from start.from): -1 to go on, else the exit code.
struct Loaded {
  SceneSpec spec;
  World world;
  StabilityReport stab;
  CheckpointKey key;
};

int load(const RunArgs& a, Loaded& l) {
  try {
    l.spec = load_scene(a.scene, a.ov);
    l.stab = build_world_releasing_discs(l.spec, l.world);  // the world has the discs: 56 B a disc less at the peak
    l.key = checkpoint_key(a.scene, a.ov);
    if (!a.resume && !l.spec.start_from.empty()) {
      load_state(l.world, l.spec.start_from);
      release_free_heap();  // the state file's read and the discs it replaced
    }
  } catch (const SceneError& e) {
    return bad(e.what());
  } catch (const std::runtime_error& e) {
    return bad(std::string("start.from: ") + e.what());
  }
  return -1;
}

// Checkpoints, --resume, --pictures' process and the output directory: -1 to go on, else the exit code.
int prepare(const RunArgs& a, Loaded& l, SceneRun& run, PictureProcess& pictures, int& cleared) {
  const double every = a.checkpoint_every < 0 ? l.spec.checkpoint_every : a.checkpoint_every;
  if (!(every / l.world.dt <= kMaxSteps)) return bad("--checkpoint-every: more than 1e12 steps of dt");
  const std::string ckpt = checkpoint_path(a.out);
  // Checkpoints every `every` simulated seconds (at step counts that are multiples);
  // SIGINT / SIGTERM stop after the current step with a final checkpoint.
  run.set_checkpoints(every > 0 ? std::max(1L, static_cast<long>(std::llround(every / l.world.dt))) : 0, ckpt, l.key);
  if (a.resume) {
    // The checkpoint replaces the fill (or start.from): the run goes on from where it was.
    if (!std::filesystem::exists(ckpt))
      return bad("--resume: no checkpoint " + ckpt + " (the run wrote none: run it without --resume)");
    try {
      run.resume(ckpt, l.key);
    } catch (const std::runtime_error& e) {
      return bad(std::string("--resume: ") + e.what());
    }
  }
  if (a.pictures) {
    std::string error;
    if (!pictures.start(a.out, a.quiet, error)) return bad("--pictures: " + error);
  }
  // Only a valid scene creates its output directory; a fresh run clears what an earlier run left.
  std::error_code ec;
  cleared = a.resume ? 0 : clear_run_outputs(a.out);
  std::filesystem::create_directories(a.out, ec);
  if (ec) return bad("--out " + a.out + ": cannot create the directory: " + ec.message());
  return -1;
}

// How the run ended: its last lines, the log written, the pictures drawn; the exit code.
int report(const RunArgs& a, Loaded& l, SceneRun& run, RunLog& log, Status status, const RunSummary& summary,
           PictureProcess& pictures, int argc, char** argv) {
  const std::string& out = a.out;
  if (status == Status::unstable) {
    log.warn("dem: unstable run: %s\n  last good state at t = %g s written to %s\n", summary.reason.c_str(),
             run.runner.last_good.time(), out.c_str());
    log.write(out, a.resume);
    return 3;
  }
  if (status == Status::interrupted) {
    log.warn("dem: interrupted by signal %d at t = %.6g s (step %ld); outputs and %s written (%s goes on)\n",
             stop_signal(), l.world.time, l.world.steps, checkpoint_path(out).c_str(), resume_command(argc, argv).c_str());
    log.write(out, a.resume);
    return 128 + stop_signal();
  }
  log.say("  %s at t = %.4f s after %ld steps; fill rest %s", to_string(status), l.world.time, l.world.steps,
          summary.rest_reached ? "reached" : "not reached");
  if (summary.rest_reached) log.say(" at t = %.4f s", summary.rest_time);
  const std::string picture_hint = a.pictures ? std::string("pictures: --pictures draws them next")
                                              : std::string("pictures: ") + DEM_PYTHON_EXE + " -m dem.compare.figures run " + shell_quote(out);
  log.say("; %.3g s wall, %.3g particle-steps/s\n  outputs in %s (%s)\n", summary.wall_seconds,
          summary.wall_seconds > 0 ? l.world.particle_steps / summary.wall_seconds : 0.0, out.c_str(), picture_hint.c_str());
  log.write(out, a.resume);
  if (a.pictures) {
    const int drawn = pictures.draw();
    if (drawn != 0) {
      std::fprintf(stderr, "dem run --pictures: the pictures were not drawn (%s exited with %d); the run's outputs are in %s\n",
                   DEM_PYTHON_EXE, drawn, out.c_str());
      return 4;
    }
  }
  return 0;
}

int run_scene(const RunArgs& a, int argc, char** argv) {
  auto loaded = std::make_unique<Loaded>();
  Loaded& l = *loaded;
  if (const int code = load(a, l); code >= 0) return code;
  SceneRun run(l.spec, l.world, a.out);
  PictureProcess pictures;  // --pictures: started once the scene is known good
  int cleared = 0;
  if (const int code = prepare(a, l, run, pictures, cleared); code >= 0) return code;
  RunLog log(!a.quiet);  // DIR/run.log, printed unless --quiet
  log.add(run_header(l.spec, l.world, l.stab));
  if (cleared > 0) log.say("  removed %d files of an earlier run from %s\n", cleared, a.out.c_str());
  run.log = &log;
  install_stop_handlers();
  if (a.resume)
    log.say("  resumed from %s at t = %.4f s (step %ld, %s)\n", checkpoint_path(a.out).c_str(), l.world.time,
            l.world.steps, run.phase_name());
  if (!a.resume && !l.spec.start_from.empty())
    log.say("  started from %s at t = %.4f s\n", l.spec.start_from.c_str(), l.world.time);
  const Status status = run.run(l.spec.progress && !a.quiet, !a.quiet);
  nlohmann::ordered_json extra;
  RunSummary summary = run.summary(extra);
  summary.command.assign(argv - 2, argv + argc);  // dem run ARGS: argv[0] and "run" precede them
  print_phase_result(run, log);
  write_outputs(a.out, l.spec, l.world, measure_loads(l.world, l.spec.profile_bin), summary, l.stab, &extra);
  run.discard_kept();  // the outputs hold it when it was needed; a checkpoint carries its own copy
  if (!a.save_to.empty() && status != Status::unstable) save_state(l.world, a.save_to);
  return report(a, l, run, log, status, summary, pictures, argc, argv);
}

}  // namespace

Command add_run(CLI::App& dem) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* run = dem.add_subcommand(
      "run", "run a scene into DIR: in this engine, or with --engine CODE in LIGGGHTS, LAMMPS or YADE");
  run->footer(kRunFooter);
  run->add_option("SCENE.toml", a->scene, "the scene (docs/scene.md)")->required()->type_name("");
  run->add_option("--out", a->out,
                  "output directory (created, or cleared of an earlier run's files unless\n"
                  "--resume; see docs/outputs.md)")
      ->required()->type_name("DIR");
  add_set_option(*run, a->ov.sets);
  run->add_flag("--quiet", a->quiet, "no header and no progress line");
  run->add_flag("--pictures", a->pictures,
                "also draw the run's pictures into DIR with matplotlib (" DEM_PYTHON_EXE " -m dem.compare.figures\n"
                "run DIR), in a Python process started with the run; none when the run stops unstable\n"
                "or interrupted; exit 4 if they fail");
  add_native_options(*run, *a);
  add_engine_options(*run, *a);
  // Words --engine's program reads that are not declared here go on to it untouched.
  run->allow_extras();
  return {run, [a, run](int argc, char** argv) {
            if (!a->engine.empty())
              return exec_python({"dem.compare.engine_run"}, words(argc, argv), "dem run --engine");
            if (!run->remaining().empty())
              return bad_usage("dem run", "unknown option or extra argument " + run->remaining().front());
            return run_scene(*a, argc, argv);
          }};
}

}  // namespace dem::cli
