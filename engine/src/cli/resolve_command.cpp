// dem resolve: the validated scene as JSON, what the comparison layer translates; and dem
// compare, which hands its arguments to the comparison layer (`python3 -m dem.compare scene ARGS`).
#include <cstdio>
#include <memory>

#include "cli/cli.hpp"
#include "io/files.hpp"
#include "io/outputs.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"
#include "scene/resolve.hpp"
#include "scene/scene.hpp"
#include "scene/units.hpp"

namespace dem::cli {

namespace {

struct ResolveArgs {
  std::string scene, out;
  SceneOverrides ov;
  bool stability = false;
};

// The time-step bounds a run of the scene prints and enforces (summary.json's "stability"), with
// the clusters' bound for every scheme: the comparison layer reads them here rather than derive
// them again. Built whatever the scene's dt, which a run would refuse above the bound.
nlohmann::ordered_json stability(SceneSpec s) {
  s.force_dt = true;
  World w;
  const StabilityReport rep = build_world(s, w);
  nlohmann::ordered_json j = stability_json(rep, s.units);
  nlohmann::ordered_json by = nlohmann::ordered_json::object();
  for (Scheme scheme : {Scheme::paper_eq18, Scheme::paper_eq19, Scheme::velocity_verlet})
    by[to_string(scheme)] = finite_or_null(cluster_dt_bound(w, scheme, default_length(s.units, kClusterTouch)).dt);
  j["dt_clusters_by_scheme"] = by;
  return j;
}

int resolve(const ResolveArgs& a) {
  try {
    const SceneSpec s = load_scene(a.scene, a.ov);
    nlohmann::json j = resolved_scene_json(s);
    if (a.stability) j["stability"] = nlohmann::json(stability(s));
    const std::string text = j.dump(1) + "\n";
    if (a.out.empty()) std::fwrite(text.data(), 1, text.size(), stdout);
    else write_file_atomic(a.out, text);
  } catch (const SceneError& e) {
    return bad(e.what());
  }
  return 0;
}

}  // namespace

Command add_resolve(CLI::App& dem) {
  auto a = std::make_shared<ResolveArgs>();
  CLI::App* r = dem.add_subcommand("resolve", "the validated scene with every value resolved (JSON)");
  r->add_option("SCENE.toml", a->scene, "the scene")->required()->type_name("");
  r->add_option("--out", a->out, "write the JSON to FILE (default: stdout)")->type_name("FILE.json");
  r->add_flag("--stability", a->stability,
              "add \"stability\": the time-step bounds a run prints (summary.json's), and the bonded clusters' "
              "bound for every scheme (dt_clusters_by_scheme)");
  add_set_option(*r, a->ov.sets);
  return {r, [a](int, char**) { return resolve(*a); }};
}

Command add_compare(CLI::App& dem) {
  CLI::App* c = dem.add_subcommand(
      "compare", "the scene (or a .list of scenes) in this engine, LIGGGHTS and YADE: agreement report (dem compare --help)");
  // Every word after `compare`, --help included, is the comparison layer's.
  c->prefix_command();
  c->set_help_flag();
  return {c, [](int argc, char** argv) { return exec_python({"dem.compare", "scene"}, words(argc, argv), "dem compare"); }};
}

}  // namespace dem::cli
