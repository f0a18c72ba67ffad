// dem ensemble: perturbed copies of a discharge, all here, one member alone (a job of a job
// array; in this engine or in a reference code), or the members gathered (merge).
#include <memory>

#include "cli/cli.hpp"
#include "io/files.hpp"
#include "physics/world.hpp"
#include "run/ensemble.hpp"
#include "scene/scene.hpp"

namespace dem::cli {

namespace {

const char* kEnsembleFooter =
    "Runs M copies of the scene (default 8) whose initial disc centres are moved by a seeded\n"
    "uniform amount in [-CM, CM] (default 1e-4 cm; 1e-6 m in an si scene), J at a time (default:\n"
    "all cores), into DIR/member_KK (each with its run.log and the files of dem run), and writes\n"
    "DIR/ensemble.json: mean and standard error of the flow rate, discs\n"
    "out at 1 s, peak/static ratios, jam fraction and flow-pattern counts.\n"
    "\n"
    "--member K runs member K alone (0-based), the same member bit for bit as in a full ensemble\n"
    "of that seed and perturbation: one job of a job array. `dem ensemble merge DIR` gathers the\n"
    "finished members into DIR/ensemble.json, the same file a full ensemble writes; it refuses\n"
    "members of another ensemble and, with --members M, any of 0..M-1 missing (docs/ensembles.md).\n"
    "--member K --engine CODE runs member K (the same perturbed start) in the reference code as\n"
    "dem run --engine does (settling --settle s, default 1 s, then the discharge), into\n"
    "DIR/member_KK; merge gathers such members (members of another code are another ensemble).\n"
    "Exit codes: 0; 2 bad input; 3 when every member was unstable; 4 when every member failed or\n"
    "one could not run.";

struct EnsembleArgs {
  std::string scene, out, engine, np, timeout;
  SceneOverrides ov;
  bool quiet = false;
  double members = 8, member = -1, seed = 1, perturb = 1e-4, jobs = 0, settle = 1.0;
  CLI::Option *perturb_opt = nullptr, *engine_opt = nullptr;
};

struct MergeArgs {
  std::string dir;
  double members = 0;  // 0: those found
  bool quiet = false;
};

void add_member_options(CLI::App& e, EnsembleArgs& a) {
  e.add_option("--members", a.members, "the number of members (default 8)")->type_name("M")->check(integer_in(1, 10000));
  e.add_option("--member", a.member, "run member K alone (0-based) into DIR/member_KK")
      ->type_name("K")->check(integer_in(0, 9999));
  e.add_option("--seed", a.seed, "the seed of the perturbations (default 1)")
      ->type_name("S")->check(integer_in(0, 9007199254740992L));
  a.perturb_opt = e.add_option("--perturb", a.perturb,
                               "each disc centre moves by a uniform amount in [-CM, CM] (default 1e-4 cm,\n"
                               "1e-6 m in an si scene)")
                      ->type_name("CM")->check(number_above(0, true));
  e.add_option("--jobs", a.jobs, "members run at a time (default: all cores)")->type_name("J")->check(integer_in(1, 100000));
  e.add_option("--dt", a.ov.dt, "time step [s], overrides integrator.dt")->type_name("S")->check(number_above(0));
  e.add_option("--scheme", a.ov.scheme, "overrides integrator.scheme (as dem run --scheme)")
      ->type_name("NAME")->check(one_of({"paper_eq18", "paper_eq19", "velocity_verlet", "velocity_verlet_onset"}));
  e.add_flag("--force-dt", a.ov.force_dt, "run even if dt is above the computed stability bound");
  e.add_flag("--no-vtu", a.ov.no_vtu,
             "the members write no VTU files and no PVD indexes, as dem run --no-vtu (no part of\n"
             "the ensemble's identity)");
  add_set_option(e, a.ov.sets)->description("change one value of the scene as dem run --set does (repeatable; merge\n"
                                                  "refuses members of other sets)");
  e.add_flag("--quiet", a.quiet, "no progress lines");
}

void add_engine_options(CLI::App& e, EnsembleArgs& a) {
  const char* g = "Options of a member in a reference code";
  a.engine_opt = e.add_option("--engine", a.engine, "with --member K: run the member in liggghts|lammps|yade")
                     ->type_name("CODE")->check(one_of({"liggghts", "lammps", "yade"}))->group(g);
  e.add_option("--np", a.np, "MPI ranks (liggghts, lammps) or yade -j N")->type_name("N")->needs(a.engine_opt)->group(g);
  e.add_option("--settle", a.settle, "the settling time [s] before the discharge opens (default 1)")
      ->type_name("S")->check(number_above(0, true))->needs(a.engine_opt)->group(g);
  e.add_option("--timeout", a.timeout, "the wall-clock limit of the program [s] (exit 4)")
      ->type_name("S")->needs(a.engine_opt)->group(g);
}

// What the command line cannot say by its declarations: "" when it is consistent.
std::string inconsistency(const EnsembleArgs& a) {
  if (a.engine.empty()) return "";
  if (a.member < 0) return "--engine runs one member: give --member K (and gather them with dem ensemble merge DIR)";
  if (a.ov.dt > 0 || !a.ov.scheme.empty() || a.ov.force_dt)  // the codes run the shared law's dt
    return "--dt, --scheme, --force-dt do not go with --engine: set the scene's value with --set";
  if (a.ov.no_vtu)  // dem.compare.engine_run writes a reference code's files, VTU included
    return "--no-vtu does not go with --engine: a member in a reference code writes the files of dem run --engine";
  return "";
}

// Member K in a reference code: its start written here, then `python3 -m dem.compare.engine_run`.
int run_engine_member(const SceneSpec& spec, const EnsembleOptions& eo, const EnsembleArgs& a) {
  const int member = static_cast<int>(a.member);
  const std::string dir = prepare_engine_member(spec, eo, member, a.out, a.engine, a.settle);
  std::vector<std::string> args = {a.scene, "--engine", a.engine, "--out", dir, "--member-start",
                                   dir + "/member_start.csv", "--settle", fmt17(a.settle)};
  if (!a.np.empty()) args.insert(args.end(), {"--np", a.np});
  if (!a.timeout.empty()) args.insert(args.end(), {"--timeout", a.timeout});
  for (const std::string& v : a.ov.sets) args.insert(args.end(), {"--set", v});
  if (a.quiet) args.push_back("--quiet");
  return exec_python({"dem.compare.engine_run"}, args, "dem ensemble --engine");
}

int run_members(const EnsembleArgs& a, int argc, char** argv) {
  // Required here, not by their declarations: `dem ensemble merge DIR` goes without them.
  if (a.scene.empty()) return bad_usage("dem ensemble", "SCENE.toml is required");
  if (a.out.empty()) return bad_usage("dem ensemble", "--out is required");
  if (const std::string why = inconsistency(a); !why.empty()) return bad(why);
  EnsembleOptions eo;
  eo.members = static_cast<int>(a.members);
  eo.seed = static_cast<unsigned long>(a.seed);
  eo.jobs = static_cast<int>(a.jobs);
  eo.perturb = a.perturb;
  try {
    SceneSpec spec = load_scene(a.scene, a.ov);
    World probe;
    build_world(spec, probe);  // checks dt against the bound
    if (!spec.start_from.empty()) return bad("dem ensemble starts from the fill: remove start.from");
    if (spec.shear_box.shear)  // its members would compress and stop: the shear runs in dem run only
      return bad("dem ensemble runs fills and discharges; a [shear] scene runs with dem run");
    eo.command.assign(argv - 2, argv + argc);  // dem ensemble ARGS
    if (a.perturb_opt->count() == 0) eo.perturb = default_length(spec.units, eo.perturb);  // 1e-4 cm in its units
    if (!a.engine.empty()) return run_engine_member(spec, eo, a);
    if (a.member >= 0) return run_member_alone(spec, eo, static_cast<int>(a.member), a.out, a.quiet);
    return run_ensemble(spec, eo, a.out, a.quiet);
  } catch (const SceneError& e) {
    return bad(e.what());
  }
}

CLI::App* add_merge(CLI::App& ensemble, MergeArgs& m) {
  CLI::App* merge = ensemble.add_subcommand("merge", "gather the finished members of DIR into DIR/ensemble.json");
  merge->footer("");
  merge->add_option("DIR", m.dir, "the ensemble's folder (its member_KK folders)")->required()->type_name("");
  merge->add_option("--members", m.members, "refuse unless members 0..M-1 are all there")
      ->type_name("M")->check(integer_in(1, 10000));
  merge->add_flag("--quiet", m.quiet, "no summary line");
  return merge;
}

}  // namespace

Command add_ensemble(CLI::App& dem) {
  auto a = std::make_shared<EnsembleArgs>();
  auto m = std::make_shared<MergeArgs>();
  CLI::App* e = dem.add_subcommand("ensemble", "run perturbed copies of a discharge into DIR (or gather them: merge)");
  e->footer(kEnsembleFooter);
  e->add_option("SCENE.toml", a->scene, "the scene (a fill, or a fill and a discharge)")->type_name("");
  e->add_option("--out", a->out, "output directory: DIR/member_KK and DIR/ensemble.json")->type_name("DIR");
  add_member_options(*e, *a);
  add_engine_options(*e, *a);
  CLI::App* merge = add_merge(*e, *m);
  return {e, [a, m, merge](int argc, char** argv) {
            if (!merge->parsed()) return run_members(*a, argc, argv);
            try {
              return merge_ensemble(m->dir, static_cast<int>(m->members), m->quiet);
            } catch (const std::runtime_error& err) {
              return bad(std::string("ensemble merge: ") + err.what());
            }
          }};
}

}  // namespace dem::cli
