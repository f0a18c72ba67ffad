// dem: command-line front end. Exit codes: 0 ok, 2 bad input, 3 unstable run, 4 a run that could
// not go on (a file it could not write or read).
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/picture_process.hpp"
#include "cli/python_path.hpp"
#include "io/out_dir.hpp"
#include "io/outputs.hpp"
#include "io/run_log.hpp"
#include "io/state.hpp"
#include "physics/elastic_params.hpp"
#include "physics/free_heap.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"
#include "run/checkpoint.hpp"
#include "run/control.hpp"
#include "run/ensemble.hpp"
#include "run/scene_run.hpp"
#include "scene/resolve.hpp"
#include "scene/scene.hpp"

using namespace dem;

namespace {

const char* kMainHelp =
    "dem " DEM_VERSION " - 2D discrete-element engine of Kiyama & Fujimura (1983)\n"
    "\n"
    "usage:\n"
    "  dem run SCENE.toml --out DIR [options]   run a scene (dem run --help)\n"
    "  dem ensemble SCENE.toml --out DIR [...]  run perturbed copies of a discharge (dem ensemble --help)\n"
    "  dem params [options]                     contact constants from elasticity, eqs. (22)-(26)\n"
    "  dem resolve SCENE.toml [--out FILE.json] the validated scene with every value resolved (JSON)\n"
    "  dem compare SCENE.toml|LIST --out DIR     the scene in this engine, LIGGGHTS and YADE: agreement report (dem compare --help)\n"
    "  dem --version                            the version and build (compiler, build type)\n"
    "\n"
    "run, ensemble, resolve and compare take --set KEY=VALUE (repeatable): one value of the scene changed\n"
    "before it is validated, as if the file said it (integrator.dt=5e-5; docs/scene.md)\n"
    "\n"
    "exit codes: 0 ok, 2 bad input, 3 unstable run, 4 a run that could not go on (a file it could not\n"
    "write or read; the message names it) or whose --pictures failed, 130/143 interrupted by SIGINT/SIGTERM\n";

const char* kRunHelp =
    "usage: dem run SCENE.toml --out DIR [--dt S] [--scheme NAME] [--end-time S] [--force-dt] [--threads N]\n"
    "               [--quiet] [--no-vtu] [--pictures] [--from STATE] [--save-state FILE] [--checkpoint-every S]\n"
    "               [--resume] [--set KEY=VALUE ...]\n"
    "       dem run SCENE.toml --engine liggghts|lammps|yade [--np N] [--settle S] [--timeout S] [--pictures] --out DIR\n"
    "\n"
    "  --out DIR       output directory (created, or cleared of an earlier run's files unless\n"
    "                  --resume; see docs/outputs.md)\n"
    "  --dt S          time step [s], overrides integrator.dt\n"
    "  --scheme NAME   paper_eq18 | paper_eq19 | velocity_verlet | velocity_verlet_onset, overrides integrator.scheme\n"
    "  --end-time S    maximum simulated time [s], overrides end.time\n"
    "  --force-dt      run even if dt is above the computed stability bound\n"
    "  --threads N     threads of the force and integration loops (integrator.threads, default 1);\n"
    "                  every N gives the bits of N = 1, the serial loop\n"
    "  --from STATE    start from a saved state (overrides start.from; skips the fill)\n"
    "  --save-state F  save the final state (positions, velocities, forces, contact history)\n"
    "  --checkpoint-every S  write DIR/checkpoint.dem every S simulated seconds (overrides\n"
    "                  output.checkpoint_every; 0: none)\n"
    "  --resume        continue from DIR/checkpoint.dem (same scene file, engine and options);\n"
    "                  the result is bit-identical to a run never stopped\n"
    "  --quiet         no header and no progress line\n"
    "  --no-vtu        no VTU files and no PVD indexes: the CSV files alone (output.vtu = \"none\")\n"
    "  --pictures      also draw the run's pictures into DIR, with PIL (compare.quick_figures: the\n"
    "                  files of compare.figures run DIR), in a Python process started with the run;\n"
    "                  none when the run stops unstable or interrupted; exit 4 if they fail\n"
    "  --engine CODE   run the scene in the real LIGGGHTS, LAMMPS or YADE with the shared law and write\n"
    "                  the same outputs (docs/compare.md, \"Running a scene in a reference code\");\n"
    "                  exit 2 when the code cannot express the scene (the field named)\n"
    "  --np N          with --engine: MPI ranks (liggghts, lammps: mpirun -np N) or yade -j N\n"
    "  --set KEY=VALUE change one value of the scene before it is validated, as if the file said it\n"
    "                  (repeatable): integrator.dt=5e-5, integrator.scheme=velocity_verlet,\n"
    "                  walls.0.material=steel (an index picks an entry of [[walls]]); VALUE is read as\n"
    "                  TOML, else as a string. A wrong key or value is refused (exit 2) like one in the\n"
    "                  file (docs/scene.md, \"Changing values from the command line\")\n"
    "\n"
    "The engine writes data (docs/outputs.md); the pictures of a run (network.png, side_walls.png and\n"
    "a discharge's frames, wall ratios and flow) are drawn by " DEM_PYTHON_EXE " -m compare.figures run DIR,\n"
    "or with the run by --pictures.\n"
    "The scene is validated completely before anything is written; a bad scene exits with 2 and\n"
    "leaves no output directory. A run that blows up (non-finite values, overlap beyond\n"
    "end.max_overlap x r_min) stops with 3 and writes the last good state. SIGINT or SIGTERM stops\n"
    "at the end of the current step, writes a checkpoint and all outputs (status \"interrupted\")\n"
    "and exits with 130 (SIGINT) or 143 (SIGTERM).\n";

const char* kEnsembleHelp =
    "usage: dem ensemble SCENE.toml --out DIR [--members M] [--seed S] [--perturb CM] [--jobs J]\n"
    "                    [--dt S] [--scheme NAME] [--force-dt] [--quiet] [--no-vtu] [--set KEY=VALUE ...]\n"
    "       dem ensemble SCENE.toml --out DIR --member K [--seed S] [--perturb CM] [...]\n"
    "       dem ensemble SCENE.toml --out DIR --member K --engine liggghts|lammps|yade [--np N]\n"
    "                    [--settle S] [--timeout S] [--seed S] [--perturb CM] [--set ...] [--quiet]\n"
    "       dem ensemble merge DIR [--members M] [--quiet]\n"
    "\n"
    "Runs M copies of the scene (default 8) whose initial disc centres are moved by a seeded\n"
    "uniform amount in [-CM, CM] (default 1e-4 cm; 1e-6 m in an si scene), J at a time (default:\n"
    "all cores), into DIR/member_KK (each with its run.log and the files of dem run), and writes\n"
    "DIR/ensemble.json: mean and standard error of the flow rate, discs\n"
    "out at 1 s, peak/static ratios, jam fraction and flow-pattern counts. --set KEY=VALUE changes\n"
    "one value of the scene as dem run --set does (repeatable; merge refuses members of other sets).\n"
    "--no-vtu: the members write no VTU files and no PVD indexes, as dem run --no-vtu (no part of\n"
    "the ensemble's identity).\n"
    "\n"
    "--member K runs member K alone (0-based), the same member bit for bit as in a full ensemble\n"
    "of that seed and perturbation: one job of a job array. `merge DIR` gathers the finished\n"
    "members into DIR/ensemble.json, the same file a full ensemble writes; it refuses members of\n"
    "another ensemble and, with --members M, any of 0..M-1 missing (docs/ensembles.md).\n"
    "--member K --engine CODE runs member K (the same perturbed start) in the reference code as\n"
    "dem run --engine does (settling --settle s, default 1 s, then the discharge), into\n"
    "DIR/member_KK; merge gathers such members (members of another code are another ensemble).\n"
    "Exit codes: 0; 3 when every member was unstable; 4 when every member failed or one could not run.\n";

const char* kParamsHelp =
    "usage: dem params [SCENE.toml] [--units cgs|si] [--E kgf/cm2,...] [--nu V] [--r L] [--rho D] [--q F]\n"
    "                  [--s V] [--g A]\n"
    "\n"
    "Prints the paper's Table 1: K_n/(rho g) [length], eta_n/(rho g) [length s] and the dt bound of\n"
    "eq. (26) for each Young's modulus E (always in kgf/cm^2, the paper's unit; default\n"
    "7.5e2,1e3,1e4,1e5,1e6), with nu = 0.3, s = K_s/K_n = 0.25 and, in the unit system chosen,\n"
    "cgs (the default): r = 1 cm, rho = 2.65 g/cm^3, line load q = 30 gf/cm (not printed in the\n"
    "paper; it reproduces Table 1), g = 980 cm/s^2; si: r = 0.01 m, rho = 2650 kg/m^3,\n"
    "q = 29.42 N/m (the same 30 gf/cm), g = 9.8 m/s^2. The system is the scene's physics.units\n"
    "when a scene is given, else --units; --r, --rho, --q (force per thickness) and --g are read in it.\n";

int bad(const std::string& msg) {
  std::fprintf(stderr, "dem: %s\n", msg.c_str());
  return 2;
}

bool number_arg(const char* s, double& v) {
  char* end = nullptr;
  v = std::strtod(s, &end);
  return end != s && *end == '\0' && std::isfinite(v);
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
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

const char* g_program = "dem";  // argv[0], for the commands the engine prints

// The command that continues an interrupted run: this one's own arguments with --resume.
std::string resume_command(int argc, char** argv) {
  std::string cmd = shell_quote(g_program) + " run";
  for (int a = 0; a < argc; ++a)
    if (std::string(argv[a]) != "--resume") cmd += " " + shell_quote(argv[a]);
  return cmd + " --resume";
}

// dem run's command line.
struct RunArgs {
  std::string scene, out, save_to;
  SceneOverrides ov;
  bool quiet = false, resume = false, pictures = false;
  double checkpoint_every = -1;  // [s] -1: the scene's output.checkpoint_every
};

// Reads the options into `a`; returns -1 to go on, or the exit code (0 after --help, 2 for bad input).
int parse_run_args(int argc, char** argv_in, RunArgs& a_) {
  // --option=value is read as --option value.
  std::vector<std::string> words;
  for (int a = 0; a < argc; ++a) {
    const std::string w = argv_in[a];
    const auto eq = w.find('=');
    if (w.rfind("--", 0) == 0 && eq != std::string::npos) {
      words.push_back(w.substr(0, eq));
      words.push_back(w.substr(eq + 1));
    } else {
      words.push_back(w);
    }
  }
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argc = static_cast<int>(argv.size());
  std::string& scene = a_.scene;
  std::string& out = a_.out;
  std::string& save_to = a_.save_to;
  SceneOverrides& ov = a_.ov;
  bool& quiet = a_.quiet;
  bool& resume = a_.resume;
  double& checkpoint_every = a_.checkpoint_every;
  for (int a = 0; a < argc; ++a) {
    const std::string k = argv[a];
    auto value = [&]() -> const char* { return a + 1 < argc ? argv[++a] : nullptr; };
    if (k == "--help" || k == "-h") {
      std::fputs(kRunHelp, stdout);
      return 0;
    } else if (k == "--out") {
      const char* v = value();
      if (!v) return bad("--out needs a directory");
      out = v;
    } else if (k == "--dt") {
      const char* v = value();
      if (!v || !number_arg(v, ov.dt) || !(ov.dt > 0)) return bad("--dt needs a number > 0");
    } else if (k == "--end-time") {
      const char* v = value();
      if (!v || !number_arg(v, ov.end_time) || !(ov.end_time > 0)) return bad("--end-time needs a number > 0");
    } else if (k == "--scheme") {
      const char* v = value();
      if (!v) return bad("--scheme needs paper_eq18, paper_eq19, velocity_verlet or velocity_verlet_onset");
      ov.scheme = v;
    } else if (k == "--force-dt") {
      ov.force_dt = true;
    } else if (k == "--no-vtu") {
      ov.no_vtu = true;
    } else if (k == "--threads") {
      const char* v = value();
      double x = 0;
      if (!v || !number_arg(v, x) || !(x >= 1 && x <= kMaxThreads && x == std::floor(x)))
        return bad("--threads needs an integer in [1, " + std::to_string(kMaxThreads) + "]");
      ov.threads = static_cast<int>(x);
    } else if (k == "--quiet") {
      quiet = true;
    } else if (k == "--pictures") {
      a_.pictures = true;
    } else if (k == "--from") {
      const char* v = value();
      if (!v) return bad("--from needs a state file");
      ov.from = v;
    } else if (k == "--checkpoint-every") {
      const char* v = value();
      if (!v || !number_arg(v, checkpoint_every) || !(checkpoint_every >= 0))
        return bad("--checkpoint-every needs a number of simulated seconds >= 0");
    } else if (k == "--resume") {
      resume = true;
    } else if (k == "--save-state") {
      const char* v = value();
      if (!v) return bad("--save-state needs a file name");
      save_to = v;
    } else if (k == "--set") {
      const char* v = value();
      if (!v || !std::strchr(v, '=')) return bad("--set needs KEY=VALUE (integrator.dt=5e-5)");
      ov.sets.push_back(v);
    } else if (!k.empty() && k[0] == '-') {
      return bad("unknown option " + k + " (see dem run --help)");
    } else if (scene.empty()) {
      scene = k;
    } else {
      return bad("more than one scene given: " + scene + ", " + k);
    }
  }
  if (scene.empty()) return bad("no scene file given (see dem run --help)");
  if (out.empty()) return bad("--out DIR is required (see dem run --help)");
  return -1;
}

// The process becomes `python3 -m MODULE... ARGS` of the comparison layer (compare/, Python), with
// this binary as its native engine (DEM_BINARY) and the source tree on its path. Returns only
// when Python cannot start (exit 4, `who` naming the command).
int exec_python(std::vector<const char*> module, int argc, char** argv, const char* who) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) setenv("DEM_BINARY", self.c_str(), 1);
  setenv("PYTHONPATH", comparison_python_path().c_str(), 1);
  std::vector<char*> args = {const_cast<char*>(DEM_PYTHON_EXE), const_cast<char*>("-m")};
  for (const char* m : module) args.push_back(const_cast<char*>(m));
  for (int k = 0; k < argc; ++k) args.push_back(argv[k]);
  args.push_back(nullptr);
  execv(DEM_PYTHON_EXE, args.data());
  std::fprintf(stderr, "%s: cannot start %s: %s\n", who, DEM_PYTHON_EXE, std::strerror(errno));
  return 4;
}

// dem run --engine CODE: `python3 -m compare.engine_run ARGS`.
int cmd_run_engine(int argc, char** argv) {
  return exec_python({"compare.engine_run"}, argc, argv, "dem run --engine");
}

// parse -> load -> build -> run the phases -> write.
int cmd_run(int argc, char** argv) {
  for (int k = 0; k < argc; ++k)
    if (!std::strncmp(argv[k], "--engine", 8)) return cmd_run_engine(argc, argv);
  RunArgs args;
  if (const int code = parse_run_args(argc, argv, args); code >= 0) return code;
  const std::string &scene = args.scene, &out = args.out, &save_to = args.save_to;
  const SceneOverrides& ov = args.ov;
  const bool quiet = args.quiet, resume = args.resume;
  PictureProcess pictures;  // --pictures: started once the scene is known good
  double checkpoint_every = args.checkpoint_every;
  SceneSpec spec;
  World world;
  StabilityReport stab;
  CheckpointKey key;
  try {
    spec = load_scene(scene, ov);
    stab = build_world_releasing_discs(spec, world);  // the world has the discs: 56 B a disc less at the peak
    key = checkpoint_key(scene, ov);
    if (!resume && !spec.start_from.empty()) {
      load_state(world, spec.start_from);
      release_free_heap();  // the state file's read and the discs it replaced
    }
  } catch (const SceneError& e) {
    return bad(e.what());
  } catch (const std::runtime_error& e) {
    return bad(std::string("start.from: ") + e.what());
  }
  if (checkpoint_every < 0) checkpoint_every = spec.checkpoint_every;
  if (!(checkpoint_every / world.dt <= kMaxSteps)) return bad("--checkpoint-every: more than 1e12 steps of dt");
  const std::string ckpt = checkpoint_path(out);
  SceneRun run(spec, world, out);
  // Checkpoints every checkpoint_every simulated seconds (at step counts that are multiples);
  // SIGINT / SIGTERM stop after the current step with a final checkpoint.
  run.set_checkpoints(checkpoint_every > 0 ? std::max(1L, static_cast<long>(std::llround(checkpoint_every / world.dt))) : 0,
                      ckpt, key);
  if (resume) {
    // The checkpoint replaces the fill (or start.from): the run goes on from where it was.
    if (!std::filesystem::exists(ckpt))
      return bad("--resume: no checkpoint " + ckpt + " (the run wrote none: run it without --resume)");
    try {
      run.resume(ckpt, key);
    } catch (const std::runtime_error& e) {
      return bad(std::string("--resume: ") + e.what());
    }
  }
  if (args.pictures) {
    std::string error;
    if (!pictures.start(out, quiet, error)) return bad("--pictures: " + error);
  }
  // Only a valid scene creates its output directory; a fresh run clears what an earlier run left.
  std::error_code ec;
  const int cleared = resume ? 0 : clear_run_outputs(out);
  std::filesystem::create_directories(out, ec);
  if (ec) return bad("--out " + out + ": cannot create the directory: " + ec.message());
  RunLog log(!quiet);  // DIR/run.log, printed unless --quiet
  log.add(run_header(spec, world, stab));
  if (cleared > 0) log.say("  removed %d files of an earlier run from %s\n", cleared, out.c_str());
  run.log = &log;
  install_stop_handlers();
  if (resume)
    log.say("  resumed from %s at t = %.4f s (step %ld, %s)\n", ckpt.c_str(), world.time, world.steps,
            run.phase_name());
  if (!resume && !spec.start_from.empty())
    log.say("  started from %s at t = %.4f s\n", spec.start_from.c_str(), world.time);
  const Status status = run.run(spec.progress && !quiet, !quiet);

  nlohmann::ordered_json extra;
  RunSummary summary = run.summary(extra);
  summary.command.assign(argv - 2, argv + argc);  // dem run ARGS: argv[0] and "run" precede them
  print_phase_result(run, log);
  write_outputs(out, spec, world, summary, stab, &extra);
  run.discard_kept();  // the outputs hold it when it was needed; a checkpoint carries its own copy
  if (!save_to.empty() && status != Status::unstable) save_state(world, save_to);
  if (status == Status::unstable) {
    log.warn("dem: unstable run: %s\n  last good state at t = %g s written to %s\n", summary.reason.c_str(),
             run.runner.last_good.time(), out.c_str());
    log.write(out, resume);
    return 3;
  }
  if (status == Status::interrupted) {
    log.warn("dem: interrupted by signal %d at t = %.6g s (step %ld); outputs and %s written (%s goes on)\n",
             stop_signal(), world.time, world.steps, ckpt.c_str(), resume_command(argc, argv).c_str());
    log.write(out, resume);
    return 128 + stop_signal();
  }
  log.say("  %s at t = %.4f s after %ld steps; fill rest %s", to_string(status), world.time, world.steps,
          summary.rest_reached ? "reached" : "not reached");
  if (summary.rest_reached) log.say(" at t = %.4f s", summary.rest_time);
  const std::string picture_hint = args.pictures ? std::string("pictures: --pictures draws them next")
                                                 : std::string("pictures: ") + DEM_PYTHON_EXE + " -m compare.figures run " + shell_quote(out);
  log.say("; %.3g s wall, %.3g particle-steps/s\n  outputs in %s (%s)\n", summary.wall_seconds,
          summary.wall_seconds > 0 ? world.particle_steps / summary.wall_seconds : 0.0, out.c_str(), picture_hint.c_str());
  log.write(out, resume);
  if (args.pictures) {
    const int drawn = pictures.draw();
    if (drawn != 0) {
      std::fprintf(stderr, "dem run --pictures: the pictures were not drawn (%s exited with %d); the run's outputs are in %s\n",
                   DEM_PYTHON_EXE, drawn, out.c_str());
      return 4;
    }
  }
  return 0;
}

int cmd_ensemble(int argc, char** argv) {
  std::string scene, out;
  SceneOverrides ov;
  EnsembleOptions eo;
  bool quiet = false, merge = false;
  int member = -1;
  // --engine CODE: the member in a reference code (compare.engine_run); its own options pass on
  std::string engine;
  std::vector<std::string> engine_args;
  for (int a = 0; a < argc; ++a) {
    const std::string k = argv[a];
    if (k == "--help" || k == "-h") {
      std::fputs(kEnsembleHelp, stdout);
      return 0;
    }
    if (k == "--engine" || k == "--np" || k == "--settle" || k == "--timeout") {
      if (a + 1 >= argc) return bad(k + " needs a value (see dem ensemble --help)");
      if (k == "--engine") engine = argv[++a];
      else {
        engine_args.push_back(k);
        engine_args.push_back(argv[++a]);
      }
      continue;
    }
    if (k == "--quiet") { quiet = true; continue; }
    if (k == "--force-dt") { ov.force_dt = true; continue; }
    if (k == "--no-vtu") { ov.no_vtu = true; continue; }
    if (a == 0 && k == "merge") { merge = true; continue; }
    if (!k.empty() && k[0] != '-') {
      if (!scene.empty()) return bad(merge ? "merge takes one folder" : "more than one scene given");
      scene = k;
      continue;
    }
    if (a + 1 >= argc) return bad(k + " needs a value (see dem ensemble --help)");
    const std::string v = argv[++a];
    double x;
    if (k == "--out") out = v;
    else if (k == "--scheme") ov.scheme = v;
    else if (k == "--set") ov.sets.push_back(v);
    else if (!number_arg(v.c_str(), x)) return bad(k + ": \"" + v + "\" is not a number");
    else if (k == "--members") { if (!(x >= 1 && x <= 10000 && x == std::floor(x))) return bad("--members must be an integer in [1, 10000]"); eo.members = static_cast<int>(x); }
    else if (k == "--member") { if (!(x >= 0 && x < 10000 && x == std::floor(x))) return bad("--member must be an integer in [0, 9999]"); member = static_cast<int>(x); }
    else if (k == "--seed") { if (!(x >= 0 && x == std::floor(x))) return bad("--seed must be an integer >= 0"); eo.seed = static_cast<unsigned long>(x); }
    else if (k == "--perturb") { if (!(x >= 0)) return bad("--perturb must be >= 0"); eo.perturb = x; }
    else if (k == "--jobs") { if (!(x >= 1 && x == std::floor(x))) return bad("--jobs must be an integer >= 1"); eo.jobs = static_cast<int>(x); }
    else if (k == "--dt") { if (!(x > 0)) return bad("--dt must be > 0"); ov.dt = x; }
    else return bad("unknown option " + k + " (see dem ensemble --help)");
  }
  if (merge) {
    if (scene.empty()) return bad("merge: no folder given (dem ensemble merge DIR)");
    bool members_given = false;
    for (int a = 0; a < argc; ++a) members_given |= std::string(argv[a]) == "--members";
    try {
      return merge_ensemble(scene, members_given ? eo.members : 0, quiet);
    } catch (const std::runtime_error& e) {
      return bad(std::string("ensemble merge: ") + e.what());
    }
  }
  if (scene.empty()) return bad("no scene file given (see dem ensemble --help)");
  if (out.empty()) return bad("--out DIR is required (see dem ensemble --help)");
  if (engine.empty() && !engine_args.empty())
    return bad(engine_args[0] + " goes with --engine CODE (see dem ensemble --help)");
  if (!engine.empty() && engine != "liggghts" && engine != "lammps" && engine != "yade")
    return bad("--engine: \"" + engine + "\" is none of liggghts, lammps, yade");
  if (!engine.empty() && member < 0)
    return bad("--engine runs one member: give --member K (and gather them with dem ensemble merge DIR)");
  if (!engine.empty() && (ov.dt > 0 || !ov.scheme.empty() || ov.force_dt))  // the codes run the shared law's dt
    return bad("--dt, --scheme, --force-dt do not go with --engine: set the scene's value with --set");
  if (!engine.empty() && ov.no_vtu)  // compare.engine_run writes a reference code's files, VTU included
    return bad("--no-vtu does not go with --engine: a member in a reference code writes the files of dem run --engine");
  try {
    SceneSpec spec = load_scene(scene, ov);
    World probe;
    build_world(spec, probe);  // checks dt against the bound
    if (!spec.start_from.empty()) return bad("dem ensemble starts from the fill: remove start.from");
    if (spec.shear_box.shear)  // its members would compress and stop: the shear runs in cmd_run only
      return bad("dem ensemble runs fills and discharges; a [shear] scene runs with dem run");
    eo.command.assign(argv - 2, argv + argc);  // dem ensemble ARGS
    bool perturb_given = false;  // else 1e-4 cm in the scene's units
    for (int a = 0; a < argc; ++a) perturb_given |= std::string(argv[a]) == "--perturb";
    if (!perturb_given) eo.perturb = default_length(spec.units, eo.perturb);
    if (!engine.empty()) {
      double settle = 1.0;  // the comparison's settling time (compare/plan.py), the member's identity
      for (std::size_t a = 0; a + 1 < engine_args.size(); a += 2)
        if (engine_args[a] == "--settle" && !(number_arg(engine_args[a + 1].c_str(), settle) && settle >= 0))
          return bad("--settle must be a number >= 0");
      const std::string dir = prepare_engine_member(spec, eo, member, out, engine, settle);
      std::vector<std::string> args = {scene, "--engine", engine, "--out", dir, "--member-start",
                                       dir + "/member_start.csv", "--settle", engine_args.empty() ? "" : ""};
      args.pop_back();
      args.push_back(fmt17(settle));
      for (std::size_t a = 0; a + 1 < engine_args.size(); a += 2)
        if (engine_args[a] != "--settle") args.insert(args.end(), {engine_args[a], engine_args[a + 1]});
      for (const std::string& v : ov.sets) args.insert(args.end(), {"--set", v});
      if (quiet) args.push_back("--quiet");
      std::vector<char*> av;
      for (std::string& v : args) av.push_back(v.data());
      return exec_python({"compare.engine_run"}, static_cast<int>(av.size()), av.data(), "dem ensemble --engine");
    }
    if (member >= 0) return run_member_alone(spec, eo, member, out, quiet);
    return run_ensemble(spec, eo, out, quiet);
  } catch (const SceneError& e) {
    return bad(e.what());
  }
}

int cmd_params(int argc, char** argv) {
  std::vector<double> E = {7.5e2, 1e3, 1e4, 1e5, 1e6};
  // The unit system: a scene's physics.units, or --units; found first, since the defaults and
  // the options' values are in it.
  Units units = Units::cgs;
  std::string scene, units_opt;
  for (int a = 0; a < argc; ++a) {
    const std::string k = argv[a];
    if (k == "--help" || k == "-h") {
      std::fputs(kParamsHelp, stdout);
      return 0;
    }
    if (!k.empty() && k[0] != '-') {
      if (!scene.empty()) return bad("params: more than one scene given (\"" + scene + "\", \"" + k + "\")");
      scene = k;
    } else if (k == "--units") {
      if (a + 1 >= argc) return bad("option --units needs a value (see dem params --help)");
      units_opt = argv[++a];
      if (units_opt != "cgs" && units_opt != "si") return bad("--units: \"" + units_opt + "\" is neither cgs nor si");
    } else {
      ++a;  // an option and its value: read below
    }
  }
  if (!scene.empty() && !units_opt.empty()) return bad("params: give a scene or --units, not both");
  if (!scene.empty()) {
    try {
      units = load_scene(scene, SceneOverrides{}).units;
    } catch (const SceneError& e) {
      return bad(e.what());
    }
  } else if (units_opt == "si") {
    units = Units::si;
  }
  const bool si = units == Units::si;
  const UnitNames u = unit_names(units);
  ElasticInputs in{};
  in.r = default_length(units, 1.0);
  in.rho = si ? 2650.0 : 2.65;
  in.g = si ? 9.8 : 980.0;
  // The line load: 30 gf/cm, in dyn/cm or N/m (1 gf/cm = 980.665 dyn/cm = 0.980665 N/m).
  const double gf_per_cm = si ? 0.980665 : 980.665;
  double q = 30.0 * gf_per_cm;
  for (int a = 0; a < argc; ++a) {
    const std::string k = argv[a];
    if (!k.empty() && k[0] != '-') continue;  // the scene
    if (a + 1 >= argc) return bad("option " + k + " needs a value (see dem params --help)");
    const char* v = argv[++a];
    double x;
    if (k == "--units") continue;
    if (k == "--E") {
      E.clear();
      std::string s = v;
      std::size_t pos = 0;
      while (pos <= s.size()) {
        const std::size_t c = s.find(',', pos);
        const std::string item = s.substr(pos, c == std::string::npos ? std::string::npos : c - pos);
        if (!number_arg(item.c_str(), x) || !(x > 0)) return bad("--E: \"" + item + "\" is not a number > 0");
        E.push_back(x);
        if (c == std::string::npos) break;
        pos = c + 1;
      }
      continue;
    }
    if (!number_arg(v, x)) return bad(k + ": \"" + std::string(v) + "\" is not a number");
    if (k == "--nu") { if (!(x >= 0 && x < 0.5)) return bad("--nu must be in [0, 0.5)"); in.nu = x; }
    else if (k == "--r") { if (!(x > 0)) return bad("--r must be > 0"); in.r = x; }
    else if (k == "--rho") { if (!(x > 0)) return bad("--rho must be > 0"); in.rho = x; }
    else if (k == "--q") { if (!(x > 0)) return bad("--q must be > 0"); q = x; }
    else if (k == "--s") { if (!(x > 0)) return bad("--s must be > 0"); in.s = x; }
    else if (k == "--g") { if (!(x > 0)) return bad("--g must be > 0"); in.g = x; }
    else return bad("unknown option " + k + " (see dem params --help)");
  }
  in.q = q;
  // E in kgf/cm^2 (the paper's unit) as dyn/cm^2 or Pa (1 kgf/cm^2 = 98066.5 Pa).
  const double e_unit = si ? kKgfPerCm2 * 0.1 : kKgfPerCm2;
  const double rg = in.rho * in.g;
  std::printf("Table 1 (%s): nu = %g, r = %g %s, rho = %g %s, q = %g %s (%g gf/cm), s = %g, g = %g %s\n",
              to_string(units), in.nu, in.r, u.length, in.rho, u.density, q, u.force, q / gf_per_cm, in.s, in.g,
              u.acceleration);
  const std::string len = std::string("[") + u.length + "]", len_s = std::string("[") + u.length + " s]";
  const std::string b_unit = std::string("b ") + len;
  std::printf("%-14s %-14s %-16s %-14s %-14s %-12s\n", "E [kgf/cm^2]", "K_n/(rho g)", "eta_n/(rho g)", "dt eq.26 [s]",
              "K_s/(rho g)", b_unit.c_str());
  std::printf("%-14s %-14s %-16s %-14s %-14s %-12s\n", "", len.c_str(), len_s.c_str(), "", len.c_str(), "");
  for (double e : E) {
    in.E = e * e_unit;
    const ElasticParams p = elastic_params(in);
    std::printf("%-14.4g %-14.4g %-16.4g %-14.4g %-14.4g %-12.4g\n", e, p.kn / rg, p.eta_n / rg, p.dt_eq26, p.ks / rg,
                p.b);
  }
  return 0;
}

}  // namespace

// The validated scene as JSON (stdout or --out): what the comparison layer translates.
int cmd_resolve(int argc, char** argv) {
  std::string scene, out;
  SceneOverrides ov;
  for (int a = 0; a < argc; ++a) {
    const std::string k = argv[a];
    if (k == "--out" && a + 1 < argc) out = argv[++a];
    else if (k == "--set" && a + 1 < argc) ov.sets.push_back(argv[++a]);
    else if (k == "--help" || k == "-h") {
      std::printf("usage: dem resolve SCENE.toml [--out FILE.json] [--set KEY=VALUE ...]\n");
      return 0;
    } else if (!k.empty() && k[0] != '-' && scene.empty()) scene = k;
    else return bad("resolve: unknown or incomplete argument \"" + k + "\"");
  }
  if (scene.empty()) return bad("resolve: no scene file given");
  try {
    const SceneSpec s = load_scene(scene, ov);
    const std::string text = resolved_scene_json(s).dump(1) + "\n";
    if (out.empty()) std::fwrite(text.data(), 1, text.size(), stdout);
    else write_file_atomic(out, text);
  } catch (const SceneError& e) {
    return bad(e.what());
  }
  return 0;
}

// dem compare: `python3 -m compare scene ARGS` (its help: dem compare --help).
int cmd_compare(int argc, char** argv) { return exec_python({"compare", "scene"}, argc, argv, "dem compare"); }

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kMainHelp, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string cmd = argv[1];
  g_program = argv[0];
  if (cmd == "--version" || cmd == "version") {
    std::printf("dem %s (%s)\n", DEM_VERSION, DEM_BUILD_ID);
    return 0;
  }
  // What the commands do not turn into an exit code of their own (a file that cannot be written
  // in the middle of a run, say) ends the run with a message naming it, not with an abort.
  try {
    if (cmd == "run") return cmd_run(argc - 2, argv + 2);
    if (cmd == "params") return cmd_params(argc - 2, argv + 2);
    if (cmd == "resolve") return cmd_resolve(argc - 2, argv + 2);
    if (cmd == "ensemble") return cmd_ensemble(argc - 2, argv + 2);
    if (cmd == "compare") return cmd_compare(argc - 2, argv + 2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dem: the run could not go on: %s\n", e.what());
    return 4;
  }
  return bad("unknown command " + cmd + " (dem --help)");
}
