// dem resolve: the validated scene as JSON, what the comparison layer translates; and dem
// compare, which hands its arguments to the comparison layer (`python3 -m compare scene ARGS`).
#include <cstdio>
#include <memory>

#include "cli/cli.hpp"
#include "io/files.hpp"
#include "scene/resolve.hpp"
#include "scene/scene.hpp"

namespace dem::cli {

namespace {

struct ResolveArgs {
  std::string scene, out;
  SceneOverrides ov;
};

int resolve(const ResolveArgs& a) {
  try {
    const SceneSpec s = load_scene(a.scene, a.ov);
    const std::string text = resolved_scene_json(s).dump(1) + "\n";
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
  add_set_option(*r, a->ov.sets);
  return {r, [a](int, char**) { return resolve(*a); }};
}

Command add_compare(CLI::App& dem) {
  CLI::App* c = dem.add_subcommand(
      "compare", "the scene (or a .list of scenes) in this engine, LIGGGHTS and YADE: agreement report (dem compare --help)");
  // Every word after `compare`, --help included, is the comparison layer's.
  c->prefix_command();
  c->set_help_flag();
  return {c, [](int argc, char** argv) { return exec_python({"compare", "scene"}, words(argc, argv), "dem compare"); }};
}

}  // namespace dem::cli
