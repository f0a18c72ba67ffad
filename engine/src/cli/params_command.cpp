// dem params: the paper's Table 1, contact constants from elasticity (eqs. (22)-(26)).
#include <cstdio>
#include <memory>
#include <sstream>

#include "cli/cli.hpp"
#include "physics/elastic_params.hpp"
#include "scene/scene.hpp"

namespace dem::cli {

namespace {

const char* kParamsFooter =
    "Prints the paper's Table 1: K_n/(rho g) [length], eta_n/(rho g) [length s] and the dt bound of\n"
    "eq. (26) for each Young's modulus E (always in kgf/cm^2, the paper's unit; default\n"
    "7.5e2,1e3,1e4,1e5,1e6), with nu = 0.3, s = K_s/K_n = 0.25 and, in the unit system chosen,\n"
    "cgs (the default): r = 1 cm, rho = 2.65 g/cm^3, line load q = 30 gf/cm (not printed in the\n"
    "paper; it reproduces Table 1), g = 980 cm/s^2; si: r = 0.01 m, rho = 2650 kg/m^3,\n"
    "q = 29.42 N/m (the same 30 gf/cm), g = 9.8 m/s^2. The system is the scene's physics.units\n"
    "when a scene is given, else --units; --r, --rho, --q (force per thickness) and --g are read in it.";

struct ParamsArgs {
  std::string scene, units, E = "7.5e2,1e3,1e4,1e5,1e6";
  double nu = 0.3, r = 0, rho = 0, q = 0, s = 0.25, g = 0;
  CLI::Option *r_opt = nullptr, *rho_opt = nullptr, *q_opt = nullptr, *g_opt = nullptr, *units_opt = nullptr;
};

std::vector<double> numbers_of(const std::string& list) {
  std::vector<double> out;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(std::strtod(item.c_str(), nullptr));
  return out;
}

// "" when every comma-separated item is a finite number > 0.
CLI::Validator positive_list() {
  const CLI::Validator one = number_above(0);
  return CLI::Validator(
      [one](std::string& list) {
        std::stringstream ss(list + ",");
        for (std::string item; std::getline(ss, item, ',');)
          if (const std::string why = one(item); !why.empty()) return why;
        return std::string();
      },
      "");
}

void print_table(const ParamsArgs& a, Units units) {
  const bool si = units == Units::si;
  const UnitNames u = unit_names(units);
  ElasticInputs in{};
  in.nu = a.nu;
  in.s = a.s;
  in.r = a.r_opt->count() ? a.r : default_length(units, 1.0);
  in.rho = a.rho_opt->count() ? a.rho : si ? 2650.0 : 2.65;
  in.g = a.g_opt->count() ? a.g : si ? 9.8 : 980.0;
  // The line load: 30 gf/cm, in dyn/cm or N/m (1 gf/cm = 980.665 dyn/cm = 0.980665 N/m).
  const double gf_per_cm = si ? 0.980665 : 980.665;
  const double q = a.q_opt->count() ? a.q : 30.0 * gf_per_cm;
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
  for (double e : numbers_of(a.E)) {
    in.E = e * e_unit;
    const ElasticParams p = elastic_params(in);
    std::printf("%-14.4g %-14.4g %-16.4g %-14.4g %-14.4g %-12.4g\n", e, p.kn / rg, p.eta_n / rg, p.dt_eq26, p.ks / rg,
                p.b);
  }
}

int params(const ParamsArgs& a) {
  // The unit system: a scene's physics.units, or --units; the defaults and the options' values are in it.
  Units units = a.units == "si" ? Units::si : Units::cgs;
  if (!a.scene.empty()) {
    try {
      units = load_scene(a.scene, SceneOverrides{}).units;
    } catch (const SceneError& e) {
      return bad(e.what());
    }
  }
  print_table(a, units);
  return 0;
}

}  // namespace

Command add_params(CLI::App& dem) {
  auto a = std::make_shared<ParamsArgs>();
  CLI::App* p = dem.add_subcommand("params", "contact constants from elasticity, eqs. (22)-(26) (the paper's Table 1)");
  p->footer(kParamsFooter);
  CLI::Option* scene = p->add_option("SCENE.toml", a->scene, "a scene: its physics.units")->type_name("");
  a->units_opt = p->add_option("--units", a->units, "cgs | si (default cgs)")
                     ->type_name("SYSTEM")->check(one_of({"cgs", "si"}))->excludes(scene);
  p->add_option("--E", a->E, "Young's moduli [kgf/cm^2], comma-separated (default 7.5e2,1e3,1e4,1e5,1e6)")
      ->type_name("E1,E2,...")->check(positive_list());
  p->add_option("--nu", a->nu, "Poisson's ratio (default 0.3)")->type_name("V")->check(number_above(0, true) & CLI::Validator(
      [](std::string& s) { return std::strtod(s.c_str(), nullptr) < 0.5 ? std::string() : "\"" + s + "\" is not < 0.5"; }, ""));
  a->r_opt = p->add_option("--r", a->r, "disc radius [length] (default 1 cm, 0.01 m)")->type_name("L")->check(number_above(0));
  a->rho_opt = p->add_option("--rho", a->rho, "density (default 2.65 g/cm^3, 2650 kg/m^3)")->type_name("D")->check(number_above(0));
  a->q_opt = p->add_option("--q", a->q, "line load [force per thickness] (default 30 gf/cm)")->type_name("F")->check(number_above(0));
  p->add_option("--s", a->s, "K_s/K_n (default 0.25)")->type_name("V")->check(number_above(0));
  a->g_opt = p->add_option("--g", a->g, "gravity (default 980 cm/s^2, 9.8 m/s^2)")->type_name("A")->check(number_above(0));
  return {p, [a](int, char**) { return params(*a); }};
}

}  // namespace dem::cli
