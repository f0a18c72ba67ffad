#include "physics/world.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "physics/parallel.hpp"

namespace dem {

int World::cpu_vector_width() {
#if defined(__x86_64__) && defined(__GNUC__)
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
    return 8;
  if (__builtin_cpu_supports("avx2")) return 4;
#endif
  return 2;
}
const int World::vector_width = World::cpu_vector_width();

void World::set_vector_width(int width) {
  if ((width != 2 && width != 4 && width != 8) || width > vector_width)
    throw std::invalid_argument("set_vector_width: " + std::to_string(width) + " doubles a vector, this processor has " +
                                std::to_string(vector_width));
  width_ = width;
}

int World::threads_for(int n) const {
  const int t = threads_allowed > 0 ? std::min(threads, threads_allowed) : threads;
  return std::max(1, std::min(t, n / kMinDiscsPerThread));
}

bool World::adjacent(int k1, int k2) const {
  const int nw = static_cast<int>(geometry.walls.size());
  if ((k1 < nw) == (k2 < nw)) return false;
  const int wall = std::min(k1, k2), point = std::max(k1, k2) - nw;
  for (int a : geometry.points[point].adjacent)
    if (a == wall) return true;
  return false;
}

void World::prepare(bool build_lists) {
  if (scheme == Scheme::velocity_verlet_onset &&
      (options.normal_spring != NormalSpring::overlap || !bonds.empty() || !moving.empty()))
    throw std::invalid_argument("velocity_verlet_onset needs the overlap spring, and no bonds or moving walls");
  select_kernel();
  geometry.link_points();
  const int slots = std::max(1, threads);
  touch_scratch_.assign(slots, std::vector<char>(geometry.obstacle_count() + 1, 0));
  dist_scratch_.assign(slots, std::vector<double>(geometry.obstacle_count() + 1, 0.0));
  cross_out_.assign(slots, {});
  cross_in_.assign(slots, {});
  cross_forces_.assign(slots, {});
  cross_gaps_.assign(slots, {});
  cross_ok_ = false;
  touching_.assign(slots, {});
  increment_sums_.assign(slots, {});
  // Only eq. (19) keeps increment arrays (increments()); they start at zero (at rest, or as set).
  Discs& d = discs;
  d.forget_kind_index();  // the discs are in
  for (auto* v : {&d.dux, &d.duy, &d.dphi}) {
    if (scheme != Scheme::paper_eq19) std::vector<double>().swap(*v);
    else v->resize(d.size(), 0.0);
  }
  if (!rotation_angle) std::vector<double>().swap(d.phi);  // an output a scene asks for
  else d.phi.resize(d.size(), 0.0);
  if (!moving.empty()) moving.motion.resize(geometry.obstacle_count());
  // The pairs' kept f_n serve the onset scheme's slip correction under the total cap alone.
  if (scheme != Scheme::velocity_verlet_onset || options.friction_cap != FrictionCap::total) onset_normals.clear();
  if (build_lists) rebuild_lists();  // keeps the history already in the lists
}

void World::drop_pair_forces() {
  pair_totals.clear();
  pair_forces_step = -1;
}

void World::size_pair_forces(std::size_t count) { pair_totals.start(count, neighbors.pairs.size()); }

void World::init() {
  prepare();
  if (scheme == Scheme::velocity_verlet_onset) return onset_forces(true);  // onset.cpp
  forces_then_move(Move::none, 0.0);  // forces at the start (Verlet's first half kick uses them)
}

void World::remove_discs(const RemovedDiscs& removed) {
  Discs& d = discs;
  const std::size_t n = d.size();
  const std::vector<int>& gone = removed.sorted;
  for (std::size_t k = 0; k < gone.size(); ++k)
    if (gone[k] < 0 || static_cast<std::size_t>(gone[k]) >= n || (k > 0 && gone[k] <= gone[k - 1]))
      throw std::logic_error("remove_discs: the removed indices are not sorted, distinct discs");
  if (gone.empty()) return;
  auto keep = [&](auto& v) { removed.compact(v); };
  d.make_ids();  // the first removal: ids are no longer the indices
  keep(d.kind); keep(d.id);  // the kinds table stays (a kind without discs costs its entry only)
  keep(d.x); keep(d.y); keep(d.vx); keep(d.vy); keep(d.omega);
  if (!d.phi.empty()) keep(d.phi);  // output.rotation_angle only
  if (!d.dux.empty()) { keep(d.dux); keep(d.duy); keep(d.dphi); }  // eq. 19 only
  keep(d.fx); keep(d.fy); keep(d.torque);
  pair_totals.compact(neighbors.pairs, removed);  // the recorded totals follow their pairs
  onset_normals.compact(removed);  // and the onset scheme's f_n (history)
  neighbors.compact(removed);
  cross_ok_ = false;
  for (int& b : force_blocks)  // the same block edges, less the discs gone below them
    b -= static_cast<int>(std::lower_bound(gone.begin(), gone.end(), b) - gone.begin());
  if (!bonds.empty()) {  // a bond goes with either of its discs; order (i, j) is kept
    std::size_t k = 0;
    for (const Bond& b : bonds) {
      const int i = removed.new_index(b.i), j = removed.new_index(b.j);
      if (i < 0 || j < 0) continue;
      Bond q = b;
      q.i = i;
      q.j = j;
      bonds[k++] = q;
    }
    bonds.resize(k);
    select_kernel();
  }
}

bool World::deactivate_wall(const std::string& name) {
  for (Wall& w : geometry.walls)
    if (w.name == name && w.active) {
      w.active = false;
      geometry.link_points();  // the slit ends now act as points
      neighbors.invalidate();
      return true;
    }
  return false;
}

World::Increments World::increments() const {
  const Discs& d = discs;
  if (scheme == Scheme::paper_eq19) return {d.dux.data(), d.duy.data(), d.dphi.data(), 1.0};
  return {d.vx.data(), d.vy.data(), d.omega.data(), dt};
}

// The sums of parallel_sum (its blocks of kSumBlock discs, each summed in order): the same bits
// as summing stored increments with it, whatever the thread count.
void World::measure_increment_sums() {
  const long n = static_cast<long>(discs.size());
  const long nb = sum_blocks(n);
  increment_sums_.resize(static_cast<std::size_t>(nb));
  const double* vx = discs.vx.data(); const double* vy = discs.vy.data();
  parallel_for(nb, static_cast<int>(std::min<long>(threads_for(static_cast<int>(n)), nb)), [&](long b) {
    double sx = 0, sy = 0;
    for (long i = b * kSumBlock, end = std::min(n, (b + 1) * kSumBlock); i < end; ++i) {
      sx += std::abs(vx[i] * dt);
      sy += std::abs(vy[i] * dt);
    }
    increment_sums_[static_cast<std::size_t>(b)].value = {sx, sy};
  });
}

void World::mean_abs_increment(double& mx, double& my) const {
  const long n = static_cast<long>(discs.size());
  const int nt = threads_for(static_cast<int>(n));
  if (verlet_family(scheme)) {
    if (increments_measured_step_ != steps)
      throw std::logic_error("mean_abs_increment: this Verlet step did not measure its increments");
    mx = my = 0;
    for (long b = 0; b < sum_blocks(n); ++b) { mx += increment_sums_[b].value[0]; my += increment_sums_[b].value[1]; }
  } else {
    const Increments u = increments();
    mx = parallel_sum(n, nt, [&](long i) { return std::abs(u.x[i] * u.factor); });
    my = parallel_sum(n, nt, [&](long i) { return std::abs(u.y[i] * u.factor); });
  }
  if (n) { mx /= static_cast<double>(n); my /= static_cast<double>(n); }
}

void World::require_velocities(const char* who) const {
  if (kick_owed_) throw std::logic_error(std::string(who) + ": the velocities are read while velocity Verlet's closing half kick is owed (pay_kick first)");
}

double World::kinetic_energy() const {
  require_velocities("kinetic_energy");
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return parallel_sum(n, threads_for(static_cast<int>(n)), [&](long i) {
    return 0.5 * d.mass(i) * (d.vx[i] * d.vx[i] + d.vy[i] * d.vy[i]) +
           0.5 / d.inv_inertia(i) * d.omega[i] * d.omega[i];
  });
}

bool World::all_finite() const {
  require_velocities("all_finite");
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return !parallel_any(n, threads_for(static_cast<int>(n)), [&](long i) {
    return !std::isfinite(d.x[i]) || !std::isfinite(d.y[i]) || !std::isfinite(d.vx[i]) ||
           !std::isfinite(d.vy[i]) || !std::isfinite(d.omega[i]);
  });
}

const char* to_string(NormalSpring v) { return v == NormalSpring::incremental ? "incremental" : "overlap"; }
const char* to_string(NoTension v) {
  return v == NoTension::elastic ? "elastic" : v == NoTension::total ? "total" : v == NoTension::overlap ? "overlap" : "none";
}
const char* to_string(FrictionCap v) {
  return v == FrictionCap::elastic ? "elastic" : v == FrictionCap::total ? "total" : "none";
}
const char* to_string(LeverArm v) { return v == LeverArm::radius ? "radius" : "contact_point"; }
const char* to_string(Scheme v) {
  return v == Scheme::paper_eq18 ? "paper_eq18" : v == Scheme::paper_eq19 ? "paper_eq19"
       : v == Scheme::velocity_verlet ? "velocity_verlet" : "velocity_verlet_onset";
}

}  // namespace dem
