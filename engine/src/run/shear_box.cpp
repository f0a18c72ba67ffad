#include "run/shear_box.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "io/outputs.hpp"
#include "scene/scene.hpp"
#include "physics/stress_planes.hpp"
#include "physics/world.hpp"

namespace dem {

using json = nlohmann::ordered_json;

namespace {

int wall_index(const World& w, const std::string& name) {
  for (std::size_t k = 0; k < w.geometry.walls.size(); ++k)
    if (w.geometry.walls[k].name == name) return static_cast<int>(k);
  throw SceneError("shear box: no wall named \"" + name + "\"");
}

}  // namespace

void build_shear_world(const SceneSpec& s, World& w) {
  if (s.clusters.enabled) {
    try {
      w.bonds = make_bonds(w.discs, s.clusters);
    } catch (const std::invalid_argument& e) {
      throw SceneError(s.file + ": clusters: " + e.what());
    }
  }
  const ShearBoxSpec& b = s.shear_box;
  if (!b.enabled) return;
  w.moving = MovingWalls{};
  w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
  for (const char* name : {"left", "right"}) {  // turning about their lower ends
    RotatingWall r;
    r.wall = wall_index(w, name);
    const Wall& wl = w.geometry.walls[r.wall];
    r.ax0 = wl.ax; r.ay0 = wl.ay; r.bx0 = wl.bx; r.by0 = wl.by;
    r.pivot_x = wl.bx;  // the walls run top -> bottom
    r.pivot_y = wl.by;
    r.reach = std::hypot(wl.ax - wl.bx, wl.ay - wl.by);
    w.moving.motion[r.wall].pivot_x = r.pivot_x;
    w.moving.motion[r.wall].pivot_y = r.pivot_y;
    w.moving.rotating.push_back(r);
  }
  RigidPlate p;
  p.wall = wall_index(w, "plate");
  const Wall& pl = w.geometry.walls[p.wall];
  p.ax0 = pl.ax; p.ay0 = pl.ay; p.bx0 = pl.bx; p.by0 = pl.by;
  p.mass = b.plate_mass;
  p.follow = b.plate_follows_walls ? 0 : -1;
  w.moving.plates.push_back(p);
}

namespace {

struct Sample {
  double t, strain, sigma, tau, ratio;
  double sigma_check, tau_check, sigma_inertia, tau_inertia;
};

double moving_max(const std::vector<Sample>& s, int half, double& at) {
  double best = -1e300;
  at = 0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const std::size_t lo = k >= static_cast<std::size_t>(half) ? k - half : 0;
    const std::size_t hi = std::min(s.size() - 1, k + half);
    double sum = 0;
    for (std::size_t q = lo; q <= hi; ++q) sum += s[q].ratio;
    const double m = sum / static_cast<double>(hi - lo + 1);
    if (m > best) { best = m; at = s[k].strain; }
  }
  return best;
}

}  // namespace

ShearResult run_shear(const SceneSpec& spec, World& w, const std::string& out, bool progress, LastGood* good) {
  const ShearBoxSpec& b = spec.shear_box;
  ShearResult res;
  const Discs& d = w.discs;
  double rmean = 0, rmin = 1e300;
  for (std::size_t i = 0; i < d.size(); ++i) {
    rmean += d.r(i);
    rmin = std::min(rmin, d.r(i));
  }
  rmean /= std::max<std::size_t>(1, d.size());
  int n_rows = 0;
  const std::vector<int> row = assign_rows(d, 0.5 * rmean, n_rows);
  const double overlap_limit = spec.max_overlap_fraction * rmin;
  const int plate = w.moving.plates.at(0).wall;
  const int left = w.moving.rotating.at(0).wall, right = w.moving.rotating.at(1).wall;
  const int floor_wall = [&] {
    for (std::size_t k = 0; k < w.geometry.walls.size(); ++k)
      if (w.geometry.walls[k].name == "floor") return static_cast<int>(k);
    return -1;
  }();
  const double weight = [&] {
    double s = 0;
    for (std::size_t i = 0; i < d.size(); ++i) s += d.mass(i) * std::hypot(w.gx, w.gy);
    return s;
  }();
  const double plate_weight = w.moving.plates[0].mass * std::hypot(w.gx, w.gy);
  const double t0 = w.time;
  const double theta_end = -std::atan(b.max_strain);
  for (RotatingWall& r : w.moving.rotating) r.omega = -b.rate;  // clockwise: the tops move to +X

  std::ostringstream series, planes;
  series << "t,strain,angle,sigma,tau,ratio,sigma_check,tau_check,sigma_inertia,tau_inertia,sigma_plate,tau_plate,"
            "plate_x,plate_y,plate_vx,plate_vy,left_fx,left_fy,left_moment,right_fx,right_fy,right_moment,floor_fx,"
            "floor_fy,contacts,sliding,bond_strain,kinetic_energy\n";
  planes << "t,strain,plane,y,contacts,sigma,tau,sigma_check,tau_check,sigma_inertia,tau_inertia\n";
  std::vector<Sample> samples;
  json snaps = json::array();
  std::filesystem::create_directories(out + "/snapshots");
  const double b_w = b.width;
  // From the start, or on from a state file's turned walls: the run that saved the state ended
  // with the sample and snapshots due at its strain, so the next ones are those past it.
  std::size_t next_snap = 0;
  long next_sample = 0;
  if (w.moving.rotating[0].theta != 0) {
    const double done = std::tan(-w.moving.rotating[0].theta);
    while (next_snap < b.snapshots.size() && done >= b.snapshots[next_snap] - 1e-12) ++next_snap;
    while (done >= static_cast<double>(next_sample) * b.sample_strain - 1e-12) ++next_sample;  // the loop's test
  }

  auto sample = [&](double strain) {
    const std::vector<double> ys = planes_between_rows(d, row, n_rows);
    const std::vector<PlaneStress> ps = plane_stresses(w, ys, b_w);
    Sample s{w.time - t0, strain, 0, 0, 0, 0, 0, 0, 0};
    for (std::size_t k = 0; k < ps.size(); ++k) {
      const PlaneStress& p = ps[k];
      s.sigma += p.sigma; s.tau += p.tau;
      s.sigma_check += p.sigma_check; s.tau_check += p.tau_check;
      s.sigma_inertia += p.sigma_inertia; s.tau_inertia += p.tau_inertia;
      planes << fmt17(s.t) << ',' << fmt17(strain) << ',' << k << ',' << fmt17(p.y) << ',' << p.contacts << ','
             << fmt17(p.sigma) << ',' << fmt17(p.tau) << ',' << fmt17(p.sigma_check) << ',' << fmt17(p.tau_check)
             << ',' << fmt17(p.sigma_inertia) << ',' << fmt17(p.tau_inertia) << '\n';
    }
    const double np = std::max<std::size_t>(1, ps.size());
    s.sigma /= np; s.tau /= np; s.sigma_check /= np; s.tau_check /= np; s.sigma_inertia /= np; s.tau_inertia /= np;
    s.ratio = s.sigma != 0 ? s.tau / s.sigma : 0;
    samples.push_back(s);
    int contacts = 0, sliding = 0;
    w.each_pair_with_forces([&](std::size_t p, const PairTotals::Force* rec) {
      const PairContact& c = w.neighbors.pairs[p];
      if ((!rec || rec->fn == 0) && c.en == 0) return;
      ++contacts;
      const PairProps& pp = w.pair(d.material(c.i), d.material(c.j));
      if (c.es != 0 && std::abs(c.es) >= pp.mu * std::max(c.en, 0.0) * (1 - 1e-12)) ++sliding;
    });
    const ObstacleMotion& mp = w.moving.motion[plate];
    const ObstacleMotion& ml = w.moving.motion[left];
    const ObstacleMotion& mr = w.moving.motion[right];
    const ObstacleMotion fl = floor_wall >= 0 ? w.moving.motion[floor_wall] : ObstacleMotion{};
    const RigidPlate& P = w.moving.plates[0];
    series << fmt17(s.t) << ',' << fmt17(strain) << ',' << fmt17(-w.moving.rotating[0].theta) << ','
           << fmt17(s.sigma) << ',' << fmt17(s.tau) << ',' << fmt17(s.ratio) << ',' << fmt17(s.sigma_check) << ','
           << fmt17(s.tau_check) << ',' << fmt17(s.sigma_inertia) << ',' << fmt17(s.tau_inertia) << ','
           << fmt17(mp.fy / b_w) << ',' << fmt17(-mp.fx / b_w) << ',' << fmt17(P.x) << ',' << fmt17(P.y) << ','
           << fmt17(P.vx) << ',' << fmt17(P.vy) << ',' << fmt17(ml.fx) << ',' << fmt17(ml.fy) << ','
           << fmt17(ml.moment) << ',' << fmt17(mr.fx) << ',' << fmt17(mr.fy) << ',' << fmt17(mr.moment) << ','
           << fmt17(fl.fx) << ',' << fmt17(fl.fy) << ',' << contacts << ',' << sliding << ','
           << fmt17(max_bond_strain(d, w.bonds)) << ',' << fmt17(w.kinetic_energy()) << '\n';
  };
  auto snapshot = [&](double strain) {
    char stem[64];
    std::snprintf(stem, sizeof stem, "%02zu", next_snap);
    write_contact_files(out + "/snapshots", std::string("contacts_") + stem, w);
    write_disc_files(out + "/snapshots", std::string("discs_") + stem, spec, d, nullptr);
    json walls = json::array();
    for (const Wall& wl : w.geometry.walls)
      walls.push_back({{"name", wl.name}, {"from", {wl.ax, wl.ay}}, {"to", {wl.bx, wl.by}}});
    snaps.push_back({{"strain", strain}, {"strain_wanted", b.snapshots[next_snap]}, {"t", w.time - t0},
                     {"contacts", std::string("contacts_") + stem + ".csv"},
                     {"discs", std::string("discs_") + stem + ".csv"}, {"walls", walls}});
    ++next_snap;
  };

  const auto c0 = std::chrono::steady_clock::now();
  auto last_print = c0;
  res.status = "sheared";
  const long max_steps =
      static_cast<long>(std::ceil(std::abs(theta_end - w.moving.rotating[0].theta) / (b.rate * w.dt))) + 2;
  // Samples and snapshots read the pair forces: every step of this small scene records them.
  w.record_pair_forces = true;
  for (long step = 0;; ++step) {
    const double strain = std::tan(-w.moving.rotating[0].theta);
    if (strain >= next_sample * b.sample_strain - 1e-12) {
      sample(strain);
      ++next_sample;
    }
    while (next_snap < b.snapshots.size() && strain >= b.snapshots[next_snap] - 1e-12) snapshot(strain);
    if (strain >= b.max_strain - 1e-12 || step > max_steps) break;
    w.step();
    if (!(w.max_overlap <= overlap_limit) || !w.all_finite()) {
      std::ostringstream os;
      os << "overlap " << w.max_overlap << " cm (limit " << overlap_limit << ") or non-finite state at shear strain "
         << strain << ", t = " << w.time << " s";
      res.status = "unstable";
      res.reason = os.str();
      break;
    }
    if (good && (step + 1) % kKeepEvery == 0) good->keep(w.discs, w.time);  // checked just above
    if (progress && (step & 1023) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_print).count() > 2.0) {
        last_print = now;
        const Sample& s = samples.back();
        std::fprintf(stderr, "\r  shear strain %.4f / %.4f  tau/sigma %.3f  %.1fs elapsed   ", strain, b.max_strain,
                     s.ratio, std::chrono::duration<double>(now - c0).count());
        std::fflush(stderr);
      }
    }
  }
  if (progress && std::chrono::duration<double>(last_print - c0).count() > 0) std::fprintf(stderr, "\n");
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();

  write_file_atomic(out + "/shear_series.csv", series.str());
  write_file_atomic(out + "/shear_planes.csv", planes.str());
  write_file_atomic(out + "/snapshots/index.json", json{{"snapshots", snaps}}.dump(1) + "\n");

  json m;
  m["width"] = b.width;
  m["rate"] = b.rate;
  m["max_strain"] = b.max_strain;
  m["plate_horizontal"] = b.plate_follows_walls ? "with_walls" : "free";
  m["plate_mass"] = w.moving.plates[0].mass;
  m["plate_weight"] = plate_weight;
  m["discs_weight"] = weight;
  m["rows"] = n_rows;
  m["planes"] = std::max(0, n_rows - 1);
  m["bonds"] = w.bonds.size();
  m["samples"] = samples.size();
  if (!samples.empty()) {
    const Sample& s0 = samples.front();
    m["sigma_initial"] = s0.sigma;
    m["sigma_plate_load"] = plate_weight / b.width;  // the plate's weight over b
    std::size_t kmax = 0;
    for (std::size_t k = 0; k < samples.size(); ++k)
      if (samples[k].ratio > samples[kmax].ratio) kmax = k;
    m["peak_ratio"] = samples[kmax].ratio;
    m["strain_at_peak"] = samples[kmax].strain;
    const int half = std::max(1, static_cast<int>(std::lround(0.005 / b.sample_strain)));
    double at = 0;
    m["peak_ratio_windowed"] = moving_max(samples, half, at);
    m["strain_at_peak_windowed"] = at;
    m["window_strain"] = (2 * half + 1) * b.sample_strain;
    m["ratio_final"] = samples.back().ratio;
    m["strain_final"] = samples.back().strain;
    double worst_static = 0, worst_identity = 0;
    for (const Sample& s : samples) {
      const double scale = std::max(std::abs(s.sigma), 1e-300);
      worst_static = std::max(worst_static, std::max(std::abs(s.sigma - s.sigma_check), std::abs(s.tau - s.tau_check)) / scale);
      worst_identity = std::max(worst_identity, std::max(std::abs(s.sigma - s.sigma_check - s.sigma_inertia),
                                                         std::abs(s.tau - s.tau_check - s.tau_inertia)) / scale);
    }
    m["check_static_max_relative"] = worst_static;
    m["check_with_inertia_max_relative"] = worst_identity;
  }
  m["plate_final"] = {w.moving.plates[0].x, w.moving.plates[0].y};
  m["bond_strain_final"] = max_bond_strain(d, w.bonds);
  m["snapshots"] = snaps.size();
  m["duration"] = w.time - t0;
  res.metrics = m;
  return res;
}

}  // namespace dem
