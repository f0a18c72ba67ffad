#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "cli/cli.hpp"
#include "cli/python_path.hpp"

namespace dem::cli {

const char* g_program = "dem";

int bad(const std::string& msg) {
  std::fprintf(stderr, "dem: %s\n", msg.c_str());
  return 2;
}

int bad_usage(const std::string& command, const std::string& msg) {
  std::fprintf(stderr, "%s: %s (see %s --help)\n", command.c_str(), msg.c_str(), command.c_str());
  return 2;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::vector<std::string> words(int argc, char** argv) { return std::vector<std::string>(argv, argv + argc); }

int exec_python(const std::vector<std::string>& module, const std::vector<std::string>& args, const char* who) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) setenv("DEM_BINARY", self.c_str(), 1);
  std::string error;
  const std::string path = comparison_python_path(error);
  if (path.empty()) {
    std::fprintf(stderr, "%s: %s\n", who, error.c_str());
    return 4;
  }
  setenv("PYTHONPATH", path.c_str(), 1);
  std::vector<std::string> all = {DEM_PYTHON_EXE, "-m"};
  all.insert(all.end(), module.begin(), module.end());
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : all) argv.push_back(w.data());
  argv.push_back(nullptr);
  execv(DEM_PYTHON_EXE, argv.data());
  std::fprintf(stderr, "%s: cannot start %s: %s\n", who, DEM_PYTHON_EXE, std::strerror(errno));
  return 4;
}

namespace {

bool read_number(const std::string& s, double& v) {
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && end != s.c_str() && *end == '\0' && std::isfinite(v);
}

std::string show_double(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

CLI::Validator number_above(double lo, bool closed) {
  const std::string want = std::string("a number ") + (closed ? ">= " : "> ") + show_double(lo);
  return CLI::Validator(
      [lo, closed, want](std::string& s) {
        double v;
        if (!read_number(s, v) || (closed ? !(v >= lo) : !(v > lo))) return "\"" + s + "\" is not " + want;
        return std::string();
      },
      "");
}

CLI::Validator integer_in(long lo, long hi) {
  const std::string want = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, want](std::string& s) {
        double v;
        if (!read_number(s, v) || v != std::floor(v) || v < lo || v > hi) return "\"" + s + "\" is not " + want;
        return std::string();
      },
      "");
}

CLI::Validator one_of(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return CLI::Validator(
      [names, list](std::string& s) {
        for (const std::string& n : names)
          if (s == n) return std::string();
        return "\"" + s + "\" is none of " + list;
      },
      "");
}

CLI::Validator key_value() {
  return CLI::Validator(
      [](std::string& s) {
        const std::size_t eq = s.find('=');
        return eq == std::string::npos || eq == 0 ? "\"" + s + "\" is not KEY=VALUE (integrator.dt=5e-5)"
                                                  : std::string();
      },
      "");
}

CLI::Option* add_set_option(CLI::App& app, std::vector<std::string>& sets) {
  return app
      .add_option("--set", sets,
                  "change one value of the scene before it is validated, as if the file said it\n"
                  "(repeatable): integrator.dt=5e-5, integrator.scheme=velocity_verlet,\n"
                  "walls.0.material=steel (an index picks an entry of [[walls]]); VALUE is read as\n"
                  "TOML, else as a string. A wrong key or value is refused (exit 2) like one in the\n"
                  "file (docs/scene.md, \"Changing values from the command line\")")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->check(key_value());
}

}  // namespace dem::cli
