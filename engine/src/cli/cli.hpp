// dem's command line: the subcommands, declared with CLI11 (options, help and parse errors from
// the same declarations), and what they share.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace dem::cli {

// A subcommand: its declaration on the app, and what runs once the command line chose it. run()
// gets the words after the subcommand's name as given (for summary.json's command line, and
// for the pass-through commands, which hand them on untouched).
struct Command {
  CLI::App* app = nullptr;
  std::function<int(int argc, char** argv)> run;
};

Command add_run(CLI::App& dem);       // run_command.cpp
Command add_ensemble(CLI::App& dem);  // ensemble_command.cpp
Command add_params(CLI::App& dem);    // params_command.cpp
Command add_resolve(CLI::App& dem);   // resolve_command.cpp
Command add_compare(CLI::App& dem);   // resolve_command.cpp: `python3 -m dem.compare scene ARGS`

extern const char* g_program;  // argv[0], for the commands the engine prints

// "dem: MSG" on stderr; the exit code of bad input, 2.
int bad(const std::string& msg);
// A command line `command` ("dem run") refuses: "dem run: MSG (see dem run --help)"; 2.
int bad_usage(const std::string& command, const std::string& msg);
std::string shell_quote(const std::string& s);

// The process becomes `python3 -m MODULE... ARGS` of the comparison layer (dem.compare, Python),
// with this binary as its native engine (DEM_BINARY) and its package dem on the path
// (python_path.hpp). Returns only when there is no package or Python cannot start (exit 4, `who`
// naming the command).
int exec_python(const std::vector<std::string>& module, const std::vector<std::string>& args, const char* who);
std::vector<std::string> words(int argc, char** argv);

// Checks of an option's value, whose message names the value and the reason (CLI11 prefixes the
// option): a finite number > lo (>= lo when `closed`), an integer in [lo, hi], one of `names`,
// KEY=VALUE.
CLI::Validator number_above(double lo, bool closed = false);
CLI::Validator integer_in(long lo, long hi);
CLI::Validator one_of(const std::vector<std::string>& names);
CLI::Validator key_value();

// --set KEY=VALUE, repeatable, as run, ensemble, resolve take it.
CLI::Option* add_set_option(CLI::App& app, std::vector<std::string>& sets);

}  // namespace dem::cli
