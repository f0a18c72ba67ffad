#include "run/shear_phase.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "io/outputs.hpp"
#include "io/state.hpp"
#include "scene/scene.hpp"
#include "physics/stress_planes.hpp"
#include "physics/world.hpp"

namespace dem {

using json = nlohmann::ordered_json;

namespace {

double moving_max(const std::vector<ShearSample>& s, int half, double& at) {
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

double strain_of(const World& w) { return std::tan(-w.moving.rotating[0].theta); }

}  // namespace

void ShearPhase::attach(World& w) {
  plate_ = w.moving.plates.at(0).wall;
  left_ = w.moving.rotating.at(0).wall;
  right_ = w.moving.rotating.at(1).wall;
  floor_ = -1;
  for (std::size_t k = 0; k < w.geometry.walls.size(); ++k)
    if (w.geometry.walls[k].name == "floor") floor_ = static_cast<int>(k);
  const double g = std::hypot(w.gx, w.gy);
  weight_ = 0;
  for (std::size_t i = 0; i < w.discs.size(); ++i) weight_ += w.discs.mass(i) * g;
  plate_weight_ = w.moving.plates[0].mass * g;
}

Status ShearPhase::begin(World& w, std::string&) {
  const ShearBoxSpec& b = spec_.shear_box;
  const Discs& d = w.discs;
  double rmean = 0;
  for (std::size_t i = 0; i < d.size(); ++i) rmean += d.r(i);
  rmean /= std::max<std::size_t>(1, d.size());
  row_ = assign_rows(d, 0.5 * rmean, n_rows_);
  t0_ = w.time;
  for (RotatingWall& r : w.moving.rotating) r.omega = -b.rate;  // clockwise: the tops move to +X
  const double theta_end = -std::atan(b.max_strain);
  max_steps_ = static_cast<long>(std::ceil(std::abs(theta_end - w.moving.rotating[0].theta) / (b.rate * w.dt))) + 2;
  series_ = "t,strain,angle,sigma,tau,ratio,sigma_check,tau_check,sigma_inertia,tau_inertia,sigma_plate,tau_plate,"
            "plate_x,plate_y,plate_vx,plate_vy,left_fx,left_fy,left_moment,right_fx,right_fy,right_moment,floor_fx,"
            "floor_fy,contacts,sliding,bond_strain,kinetic_energy\n";
  planes_ = "t,strain,plane,y,contacts,sigma,tau,sigma_check,tau_check,sigma_inertia,tau_inertia\n";
  // From the start, or on from a state file's turned walls: the run that saved the state ended
  // with the sample and snapshots due at its strain, so the next ones are those past it.
  step_ = 0;
  next_snap_ = 0;
  next_sample_ = 0;
  if (w.moving.rotating[0].theta != 0) {
    const double done = strain_of(w);
    while (next_snap_ < b.snapshots.size() && done >= b.snapshots[next_snap_] - 1e-12) ++next_snap_;
    while (done >= static_cast<double>(next_sample_) * b.sample_strain - 1e-12) ++next_sample_;  // at_strain's test
  }
  std::filesystem::create_directories(out_ + "/snapshots");
  return at_strain(w);
}

void ShearPhase::before_step(World& w, bool) {
  w.record_pair_forces = true;  // samples and snapshots read the pair forces: this small scene records every step
}

Status ShearPhase::after_step(World& w) {
  ++step_;
  return at_strain(w);
}

Status ShearPhase::at_strain(World& w) {
  const ShearBoxSpec& b = spec_.shear_box;
  const double strain = strain_of(w);
  if (strain >= next_sample_ * b.sample_strain - 1e-12) {
    sample(w, strain);
    ++next_sample_;
  }
  while (next_snap_ < b.snapshots.size() && strain >= b.snapshots[next_snap_] - 1e-12) snapshot(w, strain);
  return strain >= b.max_strain - 1e-12 || step_ > max_steps_ ? Status::sheared : Status::running;
}

void ShearPhase::sample(World& w, double strain) {
  const Discs& d = w.discs;
  const double b_w = spec_.shear_box.width;
  const std::vector<double> ys = planes_between_rows(d, row_, n_rows_);
  const std::vector<PlaneStress> ps = plane_stresses(w, ys, b_w);
  ShearSample s{w.time - t0_, strain, 0, 0, 0, 0, 0, 0, 0};
  std::ostringstream planes;
  for (std::size_t k = 0; k < ps.size(); ++k) {
    const PlaneStress& p = ps[k];
    s.sigma += p.sigma; s.tau += p.tau;
    s.sigma_check += p.sigma_check; s.tau_check += p.tau_check;
    s.sigma_inertia += p.sigma_inertia; s.tau_inertia += p.tau_inertia;
    planes << digits17(s.t) << ',' << digits17(strain) << ',' << k << ',' << digits17(p.y) << ',' << p.contacts << ','
           << digits17(p.sigma) << ',' << digits17(p.tau) << ',' << digits17(p.sigma_check) << ',' << digits17(p.tau_check)
           << ',' << digits17(p.sigma_inertia) << ',' << digits17(p.tau_inertia) << '\n';
  }
  planes_ += planes.str();
  const double np = std::max<std::size_t>(1, ps.size());
  s.sigma /= np; s.tau /= np; s.sigma_check /= np; s.tau_check /= np; s.sigma_inertia /= np; s.tau_inertia /= np;
  s.ratio = s.sigma != 0 ? s.tau / s.sigma : 0;
  samples_.push_back(s);
  int contacts = 0, sliding = 0;
  w.each_pair_with_forces([&](std::size_t p, const PairTotals::Force* rec) {
    const PairContact& c = w.neighbors.pairs[p];
    if ((!rec || rec->fn == 0) && c.en == 0) return;
    ++contacts;
    const PairProps& pp = w.pair(d.material(c.i), d.material(c.j));
    if (c.es != 0 && std::abs(c.es) >= pp.mu * std::max(c.en, 0.0) * (1 - 1e-12)) ++sliding;
  });
  const ObstacleMotion& mp = w.moving.motion[plate_];
  const ObstacleMotion& ml = w.moving.motion[left_];
  const ObstacleMotion& mr = w.moving.motion[right_];
  const ObstacleMotion fl = floor_ >= 0 ? w.moving.motion[floor_] : ObstacleMotion{};
  const RigidPlate& P = w.moving.plates[0];
  std::ostringstream series;
  series << digits17(s.t) << ',' << digits17(strain) << ',' << digits17(-w.moving.rotating[0].theta) << ','
         << digits17(s.sigma) << ',' << digits17(s.tau) << ',' << digits17(s.ratio) << ',' << digits17(s.sigma_check) << ','
         << digits17(s.tau_check) << ',' << digits17(s.sigma_inertia) << ',' << digits17(s.tau_inertia) << ','
         << digits17(mp.fy / b_w) << ',' << digits17(-mp.fx / b_w) << ',' << digits17(P.x) << ',' << digits17(P.y) << ','
         << digits17(P.vx) << ',' << digits17(P.vy) << ',' << digits17(ml.fx) << ',' << digits17(ml.fy) << ','
         << digits17(ml.moment) << ',' << digits17(mr.fx) << ',' << digits17(mr.fy) << ',' << digits17(mr.moment) << ','
         << digits17(fl.fx) << ',' << digits17(fl.fy) << ',' << contacts << ',' << sliding << ','
         << digits17(max_bond_strain(d, w.bonds)) << ',' << digits17(w.kinetic_energy()) << '\n';
  series_ += series.str();
}

void ShearPhase::snapshot(World& w, double strain) {
  char stem[64];
  std::snprintf(stem, sizeof stem, "%02zu", next_snap_);
  record->phase_snapshot(w, stem);
  json walls = json::array();
  for (const Wall& wl : w.geometry.walls)
    walls.push_back({{"name", wl.name}, {"from", {wl.ax, wl.ay}}, {"to", {wl.bx, wl.by}}});
  snaps_.push_back({{"strain", strain}, {"strain_wanted", spec_.shear_box.snapshots[next_snap_]}, {"t", w.time - t0_},
                    {"contacts", std::string("contacts_") + stem + ".csv"},
                    {"discs", std::string("discs_") + stem + ".csv"}, {"walls", walls}});
  ++next_snap_;
}

std::string ShearPhase::progress(const World&) const {
  char buf[120];
  std::snprintf(buf, sizeof buf, "shear strain %.4f / %.4f  tau/sigma %.3f",
                samples_.empty() ? 0.0 : samples_.back().strain, spec_.shear_box.max_strain,
                samples_.empty() ? 0.0 : samples_.back().ratio);
  return buf;
}

double ShearPhase::fraction(const World& w) const {
  return spec_.shear_box.max_strain > 0 ? std::min(1.0, strain_of(w) / spec_.shear_box.max_strain) : 1.0;
}

void ShearPhase::save(BinaryOut& o) const {
  o.put(step_); o.put(max_steps_); o.put(next_sample_); o.put<std::uint64_t>(next_snap_);
  o.put(t0_); o.put(n_rows_);
  o.vec(row_);
  o.vec(samples_);
  o.str(series_);
  o.str(planes_);
  o.str(snaps_.dump());
}

void ShearPhase::load(BinaryIn& r) {
  step_ = r.get<long>(); max_steps_ = r.get<long>(); next_sample_ = r.get<long>();
  next_snap_ = r.get<std::uint64_t>();
  t0_ = r.get<double>(); n_rows_ = r.get<int>();
  r.vec(row_);
  r.vec(samples_);
  series_ = r.str();
  planes_ = r.str();
  try {
    snaps_ = json::parse(r.str());
  } catch (const json::exception&) {
    r.fail("corrupt shear state (snapshots)");
  }
  if (next_snap_ > spec_.shear_box.snapshots.size()) r.fail("corrupt shear state (snapshots)");
}

void ShearPhase::finish(World& w, Status) {
  const ShearBoxSpec& b = spec_.shear_box;
  const Discs& d = w.discs;
  write_file_atomic(out_ + "/shear_series.csv", series_);
  write_file_atomic(out_ + "/shear_planes.csv", planes_);
  write_file_atomic(out_ + "/snapshots/index.json", json{{"snapshots", snaps_}}.dump(1) + "\n");

  json m;
  m["width"] = b.width;
  m["rate"] = b.rate;
  m["max_strain"] = b.max_strain;
  m["plate_horizontal"] = b.plate_follows_walls ? "with_walls" : "free";
  m["plate_mass"] = w.moving.plates[0].mass;
  m["plate_weight"] = plate_weight_;
  m["discs_weight"] = weight_;
  m["rows"] = n_rows_;
  m["planes"] = std::max(0, n_rows_ - 1);
  m["bonds"] = w.bonds.size();
  m["samples"] = samples_.size();
  if (!samples_.empty()) {
    const ShearSample& s0 = samples_.front();
    m["sigma_initial"] = s0.sigma;
    m["sigma_plate_load"] = plate_weight_ / b.width;  // the plate's weight over b
    std::size_t kmax = 0;
    for (std::size_t k = 0; k < samples_.size(); ++k)
      if (samples_[k].ratio > samples_[kmax].ratio) kmax = k;
    m["peak_ratio"] = samples_[kmax].ratio;
    m["strain_at_peak"] = samples_[kmax].strain;
    const int half = std::max(1, static_cast<int>(std::lround(0.005 / b.sample_strain)));
    double at = 0;
    m["peak_ratio_windowed"] = moving_max(samples_, half, at);
    m["strain_at_peak_windowed"] = at;
    m["window_strain"] = (2 * half + 1) * b.sample_strain;
    m["ratio_final"] = samples_.back().ratio;
    m["strain_final"] = samples_.back().strain;
    double worst_static = 0, worst_identity = 0;
    for (const ShearSample& s : samples_) {
      const double scale = std::max(std::abs(s.sigma), 1e-300);
      worst_static = std::max(worst_static, std::max(std::abs(s.sigma - s.sigma_check), std::abs(s.tau - s.tau_check)) / scale);
      worst_identity = std::max(worst_identity, std::max(std::abs(s.sigma - s.sigma_check - s.sigma_inertia),
                                                         std::abs(s.tau - s.tau_check - s.tau_inertia)) / scale);
    }
    m["check_static_max_relative"] = worst_static;
    m["check_with_inertia_max_relative"] = worst_identity;
    outcome_ = {samples_.size(), samples_.back().strain, samples_[kmax].ratio, samples_[kmax].strain,
                m["peak_ratio_windowed"].get<double>(), s0.sigma};
  }
  m["plate_final"] = {w.moving.plates[0].x, w.moving.plates[0].y};
  m["bond_strain_final"] = max_bond_strain(d, w.bonds);
  m["snapshots"] = snaps_.size();
  m["duration"] = w.time - t0_;
  metrics_ = m;
}

}  // namespace dem
