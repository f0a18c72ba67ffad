// dem: command-line front end; its subcommands are declared in cli/*_command.cpp (CLI11).
// Exit codes: 0 ok, 2 bad input, 3 unstable run, 4 a run that could not go on (a file it could
// not write or read), 130/143 interrupted by SIGINT/SIGTERM.
#include <cstdio>
#include <cstring>
#include <exception>

#include "cli/cli.hpp"
#include "cli/python_path.hpp"

using namespace dem;

namespace {

const char* kFooter =
    "run, ensemble, resolve and compare take --set KEY=VALUE (repeatable): one value of the scene changed\n"
    "before it is validated, as if the file said it (integrator.dt=5e-5; docs/scene.md)\n"
    "\n"
    "exit codes: 0 ok, 2 bad input (the message names the option or the field and the reason), 3 unstable\n"
    "run, 4 a run that could not go on (a file it could not write or read; the message names it) or whose\n"
    "--pictures failed, 130/143 interrupted by SIGINT/SIGTERM";

// The subcommand the command line chose, deepest first ("ensemble merge"), or nullptr.
const CLI::App* chosen(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) {
    const CLI::App* deeper = chosen(*sub);
    return deeper ? deeper : sub;
  }
  return nullptr;
}

std::string command_path(const CLI::App* sub) {
  std::string path;
  for (; sub && sub->get_parent(); sub = sub->get_parent()) path = " " + sub->get_name() + path;
  return "dem" + path;
}

// A command line the declarations refuse: one line naming the option and the reason; exit 2.
int parse_error(const CLI::App& app, const CLI::ParseError& e) {
  const CLI::App* sub = chosen(app);
  if (!sub && !app.remaining().empty())
    return cli::bad_usage("dem", "unknown command " + app.remaining().front());
  return cli::bad_usage(command_path(sub), e.what());
}

// `dem --version`: the version and build, and the Python package that `dem compare`,
// `--pictures` and `--engine` run (an installed one, the build tree's, or none).
std::string version_text() {
  std::string error;
  const std::string root = dem::python_package_root(error);
  return std::string("dem ") + DEM_VERSION + " (" + DEM_BUILD_ID + ")\npython package: " +
         (root.empty() ? "none (" + error + ")" : root + "/dem");
}

}  // namespace

int main(int argc, char** argv) {
  cli::g_program = argv[0];
  CLI::App app("dem " DEM_VERSION " - 2D discrete-element engine of Kiyama & Fujimura (1983)", "dem");
  app.get_formatter()->label("Usage", "usage");
  app.get_formatter()->column_width(28);
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // a repeated option: the last
  app.set_version_flag("--version", version_text, "the version, the build (compiler, build type) and the Python package it runs");
  app.require_subcommand(1);
  const std::vector<cli::Command> commands = {cli::add_run(app), cli::add_ensemble(app), cli::add_params(app),
                                              cli::add_resolve(app), cli::add_compare(app)};
  CLI::App* version = app.add_subcommand("version", "")->group("");  // as --version
  app.footer(kFooter);
  if (argc < 2) {
    std::fputs(app.help().c_str(), stderr);
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version: on stdout
    return parse_error(app, e);
  }
  if (version->parsed()) {
    std::printf("%s\n", version_text().c_str());
    return 0;
  }
  for (const cli::Command& c : commands) {
    if (!c.app->parsed()) continue;
    // The words after the subcommand's name go to it as given (the root takes no option but --help).
    int at = 1;
    while (at < argc && c.app->get_name() != argv[at]) ++at;
    // What the commands do not turn into an exit code of their own (a file that cannot be
    // written in the middle of a run, say) ends the run with a message naming it, not an abort.
    try {
      return c.run(argc - at - 1, argv + at + 1);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dem: the run could not go on: %s\n", e.what());
      return 4;
    }
  }
  return 2;
}
