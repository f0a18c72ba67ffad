#include "io/run_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "io/files.hpp"

namespace dem {

namespace {

std::string vformat(const char* format, va_list args) {
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  std::vector<char> buf(static_cast<std::size_t>(std::max(n, 0)) + 1);
  std::vsnprintf(buf.data(), buf.size(), format, args);
  return std::string(buf.data(), static_cast<std::size_t>(std::max(n, 0)));
}

std::string format(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* f, ...) {
  va_list a;
  va_start(a, f);
  std::string s = vformat(f, a);
  va_end(a);
  return s;
}

// The wait setting libgomp runs with, for the header.
std::string barrier_wait() {
  for (const char* v : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"})
    if (const char* x = std::getenv(v)) return std::string(v) + "=" + x;
  return "libgomp's default";
}

}  // namespace

std::string run_header(const SceneSpec& s, const World& w, const StabilityReport& st) {
  const UnitNames u = unit_names(s.units);
  std::string h;
  h += format("dem %s | scene %s (%s)\n", DEM_VERSION, s.name.c_str(), s.file.c_str());
  h += format("  fill: %s\n", s.fill_summary.c_str());
  h += format("  N = %zu discs, %zu walls, %zu points; gravity (%g, %g) %s\n", w.discs.size(),
              w.geometry.walls.size(), w.geometry.points.size(), w.gx, w.gy, u.acceleration);
  h += format("  units %s: lengths in %s, density %s, forces per unit thickness in %s, energies in %s\n",
              to_string(s.units), u.length, u.density, u.force, u.energy);
  h += format("  scheme %s, dt = %.4g s%s, end time %g s%s, threads %d%s\n", to_string(w.scheme), w.dt,
              s.force_dt ? " (forced)" : "", s.end_time, s.stop_at_rest ? " or rest" : "", w.threads,
              w.threads > 1 ? (std::string(" (barriers: ") + barrier_wait() +
                               (s.thread_choice ? "; or 1, whichever is faster now: integrator.thread_choice" : "") + ")")
                                  .c_str()
                            : "");
  h += format("  contact: normal_spring %s, no_tension %s, friction_cap %s, lever_arm %s\n",
              to_string(w.options.normal_spring), to_string(w.options.no_tension), to_string(w.options.friction_cap),
              to_string(w.options.lever_arm));
  h += format("  kernel: shear %s, dashpots %s, bonds %s, moving walls %s (compiled out when off); %d doubles a vector\n",
              w.kernel_shear ? "on" : "off", w.kernel_dashpots ? "on" : "off", w.bonds.empty() ? "off" : "on",
              w.moving.empty() ? "off" : "on", World::vector_width);
  h += format("  %-14s %9s %9s %7s %9s %6s %7s | dt bounds [s]: %-9s %-9s %-9s %-9s %-9s\n", "pair", "m*", "omega0",
              "zeta_n", "t_c", "e", "zeta_t", "normal", "tangent", "eq.26", "eq.21", "rot z=4");
  for (const auto& p : st.pairs) {
    char tc[32];
    if (std::isfinite(p.t_contact)) std::snprintf(tc, sizeof tc, "%9.3e", p.t_contact);
    else std::snprintf(tc, sizeof tc, "%9s", "overdamp");
    h += format("  %-14s %9.4g %9.4g %7.4f %s %6.3f %7.4f |  %-9.3e %-9.3e %-9.3e %-9.3e %-9.3e\n", p.name.c_str(),
                p.m_eff, p.omega0, p.zeta_n, tc, p.restitution, p.zeta_t, p.dt_normal, p.dt_tangential, p.dt_eq26,
                p.dt_eq21, p.dt_rot_z4);
  }
  h += format("  (each row of the lightest discs of its materials; m* in %s, omega0 in 1/s, t_c in s)\n", u.mass);
  h += format("  stability bound of %s: %.4g s (single contact %.4g s, rotation on 4 contacts %.4g s), set by %s;"
              " dt/bound = %.3f\n", to_string(w.scheme), st.dt_bound, st.dt_single, st.dt_rot_z4, st.limited_by.c_str(),
              w.dt / st.dt_bound);
  if (std::isfinite(st.clusters.dt))
    h += format("  bonded clusters (%d distinct shapes, neighbours held, contacts sticking): bound %.4g s, set by a"
                " cluster of %d discs\n", st.clusters.shapes, st.clusters.dt, st.clusters.discs);
  if (st.clusters.skipped > 0)
    h += format("  warning: %d clusters of more than %d discs are not in the bound (their step matrices are too"
                " large to examine)\n", st.clusters.skipped, kClusterMaxDiscs);
  if (w.dt > st.dt_rot_z6)
    h += format("  warning: dt is above %.4g s, the bound for a disc whose rotation is held by 6 sticking contacts"
                " (dense packings)\n", st.dt_rot_z6);
  return h;
}

void RunLog::add(const std::string& text, bool to_stderr) {
  text_ += text;
  if (echo_) {
    std::fputs(text.c_str(), to_stderr ? stderr : stdout);
    std::fflush(to_stderr ? stderr : stdout);
  }
}

void RunLog::say(const char* f, ...) {
  va_list a;
  va_start(a, f);
  const std::string s = vformat(f, a);
  va_end(a);
  add(s);
}

void RunLog::warn(const char* f, ...) {
  va_list a;
  va_start(a, f);
  const std::string s = vformat(f, a);
  va_end(a);
  text_ += s;
  std::fputs(s.c_str(), stderr);  // warnings are printed also without echo (--quiet)
  std::fflush(stderr);
}

void RunLog::write(const std::string& dir, bool append) const {
  std::string before;
  if (append) {
    std::ifstream in(dir + "/run.log", std::ios::binary);
    std::ostringstream o;
    o << in.rdbuf();
    before = o.str();
  }
  write_file_atomic(dir + "/run.log", before + text_);
}

}  // namespace dem
