// velocity_verlet_onset's force pass (onset.cpp describes the scheme): the law on the predicted
// velocities and the impulses a contact or a slip that started inside the step missed. Included
// by the kernel list (kernel_list.cpp) alone, which compiles it for the rows of the overlap spring.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "physics/contact_frame.hpp"
#include "physics/contact_law.hpp"
#include "physics/world.hpp"

namespace dem {

namespace onset {

// The impulse (normal, shear) a contact that started at the fraction 1 - phi of the step missed:
// the trapezoid over the part in contact, phi dt/2 (F_touch + F_end), less Verlet's dt/2 F_end
// (its force at the step's start was 0).
inline double onset_impulse(double phi, double dt, double f_touch, double f_end) {
  return 0.5 * dt * (phi * f_touch - (1 - phi) * f_end);
}

// The shear impulse a slip that started at the fraction theta of the step missed: the trapezoid
// of each part, dt/2 (theta (F_start + s_cap + d_s) + (1 - theta) 2 s_cap), less Verlet's
// dt/2 (F_start + s_cap), with F_start = s_start + d_s (it stuck at the start, its dashpot d_s on):
// dt/2 ((2 theta - 1) d_s + (1 - theta) (s_cap - s_start)).
inline double slip_impulse(double theta, double dt, double d_s, double s_start, double s_cap) {
  return 0.5 * dt * ((2 * theta - 1) * d_s + (1 - theta) * (s_cap - s_start));
}

// Where in the step the spring s_start + tau (s_trial - s_start) met the cap cap0 + tau (cap1 -
// cap0), in [0, 1] (a contact that stuck at the start and slides at the end).
inline double slip_fraction(double s_start, double s_trial, double cap0, double cap1) {
  const double gap = cap0 - std::abs(s_start);
  const double closing = (std::abs(s_trial) - std::abs(s_start)) - (cap1 - cap0);
  return closing > 0 ? std::clamp(gap / closing, 0.0, 1.0) : 1.0;
}

// The cap of eq. (13) for the given forces (the law's own rule, contact_law.hpp).
template <FrictionCap FC>
inline double coulomb_cap(const PairProps& p, double en, double fn) {
  return p.mu * (FC == FrictionCap::elastic ? std::max(en, 0.0) : std::abs(fn));
}

// One contact, seen by the scheme: the law with its dashpots on the predicted increments, the
// onset and slip corrections. du: spring increments (v(t + dt/2) dt); dash: dashpot increments
// (predicted v(t + dt) dt). en, es: history; cap0: the cap at the step's start where known
// (negative: unknown). Out: fn, fs at t + dt and the missed impulses jn, js.
template <NoTension NT, FrictionCap FC>
inline void onset_contact(const PairProps& p, double overlap, double du_n, double du_s, double dash_n, double dash_s,
                          double dt, double cap0, double& en, double& es, double& fn, double& fs, double& jn,
                          double& js) {
  const double inv_dt = 1.0 / dt;
  jn = js = 0;
  // (2) apart at the step's start: in contact for the fraction phi of it.
  const double phi = du_n > overlap ? overlap / du_n : 1.0;
  const double du_s_touch = phi * du_s;
  const double es_start = phi < 1 ? 0.0 : es;
  const double s_trial = es_start + p.ks * du_s_touch;  // the spring before the cap (the law's (10a))
  contact_law_dash<NormalSpring::overlap, NT, FC>(p, overlap, du_n, du_s_touch, dash_n, dash_s, inv_dt, en, es, fn, fs);
  if (phi < 1) {
    double e0 = 0, s0 = 0, fn0, fs0;  // the law at the touch: zero overlap, the dashpots alone
    contact_law_dash<NormalSpring::overlap, NT, FC>(p, 0.0, 0.0, 0.0, dash_n, dash_s, inv_dt, e0, s0, fn0, fs0);
    jn = onset_impulse(phi, dt, fn0, fn);
    js = onset_impulse(phi, dt, fs0, fs);
    return;
  }
  // (3) stuck at the start (|e_s| below the known cap), sliding at the end (the law capped e_s).
  const double cap1 = coulomb_cap<FC>(p, en, fn);
  if (cap0 >= 0 && std::abs(es_start) < cap0 && std::abs(s_trial) > cap1 && fn != 0) {
    const double theta = slip_fraction(es_start, s_trial, cap0, cap1);
    js = slip_impulse(theta, dt, p.eta_s * dash_s * inv_dt, es_start, es);
  }
}

// The predicted velocity of disc i at t + dt (v the half step's, v0 the step start's), times h.
inline double predicted(const std::vector<double>& v, const std::vector<double>& v0, std::size_t i, double h) {
  return (2 * v[i] - v0[i]) * h;
}

}  // namespace onset

template <NoTension NT, FrictionCap FC, LeverArm LA>
void World::onset_forces_law(bool start) {
  Discs& d = discs;
  const std::size_t n = d.size();
  const double hs = start ? 0.0 : dt;  // the springs' increments v dt: none at the start
  onset_jx_.assign(n, 0.0);
  onset_jy_.assign(n, 0.0);
  onset_jt_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {  // (15): m_i g, no moment
    d.fx[i] = d.mass(i) * gx;
    d.fy[i] = d.mass(i) * gy;
    d.torque[i] = 0;
  }
  double worst = 0;
  onset_pairs<NT, FC, LA>(hs, worst);
  onset_walls<NT, FC, LA>(hs, worst);
  max_overlap = worst;
  if (record_pair_forces) pair_forces_step = steps + 1;
}

// Disc pairs, in list order (the sums of (15) in the order of the other schemes' serial pass).
// hs: the springs' increments' factor (dt, or 0 at the start); worst: the largest overlap so far.
template <NoTension NT, FrictionCap FC, LeverArm LA>
__attribute__((always_inline)) inline void World::onset_pairs(double hs, double& worst) {
  Discs& d = discs;
  const double h = dt;
  const auto pred = [&](const std::vector<double>& v, const std::vector<double>& v0, std::size_t i) {
    return onset::predicted(v, v0, i, h);
  };
  auto& pairs = neighbors.pairs;
  const bool record = record_pair_forces;
  PairTotals::Force* rec = nullptr;
  std::uint64_t* bits = nullptr;
  if (record) {
    size_pair_forces(touching_pairs(0, pairs.size()));
    rec = pair_totals.forces();
    bits = pair_totals.bits();
  } else if (pair_totals.allocated()) {
    drop_pair_forces();
  }
  // friction_cap = "total": the cap at a step's start is mu |f_n(t)|, f_n(t) what the law gave
  // the pair at the last step's end (onset_normals, read and replaced in list order).
  constexpr bool kTotalCap = FC == FrictionCap::total;
  const PairNormals::Record* last_at = onset_normals.begin();
  const PairNormals::Record* const last_end = onset_normals.end();
  PairNormals::Record* kept = nullptr;
  PairNormals::Record* kept_end = nullptr;
  if constexpr (kTotalCap) {
    kept = onset_normals.start_pass();
    kept_end = onset_normals.room_end();
  }
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    PairContact& c = pairs[q];
    const int i = c.i, j = c.j;
    const double ri = d.r(i), rj = d.r(j);
    const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
    const double R2 = dx * dx + dy * dy;
    if (apart(R2, ri + rj)) {  // (3): the contact and its history end
      c.en = c.es = 0;
      continue;
    }
    const double R = std::sqrt(R2);
    const UnitNormal nrm = unit_normal(dx, dy, R);  // (4)
    const double overlap = ri + rj - R;
    const double ai = LA == LeverArm::contact_point ? ri - 0.5 * overlap : ri;
    const double aj = LA == LeverArm::contact_point ? rj - 0.5 * overlap : rj;
    const double ddx = d.vx[i] * hs - d.vx[j] * hs, ddy = d.vy[i] * hs - d.vy[j] * hs;  // (5): du_i - du_j
    const double du_n = normal_increment(ddx, ddy, nrm);
    const double du_s = shear_increment(ddx, ddy, nrm, ai * (d.omega[i] * hs), aj * (d.omega[j] * hs));
    const double pdx = pred(d.vx, onset_vx_, i) - pred(d.vx, onset_vx_, j);
    const double pdy = pred(d.vy, onset_vy_, i) - pred(d.vy, onset_vy_, j);
    const double dash_n = normal_increment(pdx, pdy, nrm);
    const double dash_s = shear_increment(pdx, pdy, nrm, ai * pred(d.omega, onset_om_, i), aj * pred(d.omega, onset_om_, j));
    const PairProps& p = pair(d.material(i), d.material(j));
    // The cap at the step's start: friction_cap elastic, from e_n (K_n times that overlap);
    // total, from the pair's kept f_n, unknown (-1) where it did not touch at the last step's end.
    double cap0;
    if constexpr (kTotalCap) {
      const PairNormals::Record* r0 = PairNormals::last(last_at, last_end, PairNormals::key(i, j));
      cap0 = r0 ? onset::coulomb_cap<FC>(p, c.en, r0->fn) : -1.0;
    } else {
      cap0 = p.mu * std::max(c.en, 0.0);
    }
    double fn, fs, jn, js;
    onset::onset_contact<NT, FC>(p, overlap, du_n, du_s, dash_n, dash_s, h, cap0, c.en, c.es, fn, fs, jn, js);
    if constexpr (kTotalCap) {
      if (__builtin_expect(kept == kept_end, 0)) {
        kept = onset_normals.grow(kept);
        kept_end = onset_normals.room_end();
      }
      *kept++ = PairNormals::Record{PairNormals::key(i, j), fn};
    }
    worst = std::max(worst, overlap);
    const ContactForce f = contact_force(fn, fs, nrm);  // (15a), (15b): on i
    d.fx[i] += f.x; d.fy[i] += f.y;
    d.fx[j] -= f.x; d.fy[j] -= f.y;
    d.torque[i] -= contact_moment(ai, fs);
    d.torque[j] -= contact_moment(aj, fs);
    const ContactForce J = contact_force(jn, js, nrm);
    onset_jx_[i] += J.x; onset_jy_[i] += J.y;
    onset_jx_[j] -= J.x; onset_jy_[j] -= J.y;
    onset_jt_[i] -= contact_moment(ai, js);
    onset_jt_[j] -= contact_moment(aj, js);
    if (record) {
      *rec++ = PairTotals::Force{fn, fs};
      bits[q >> 6] |= std::uint64_t{1} << (q & 63);
    }
  }
  if constexpr (kTotalCap) onset_normals.end_pass(kept);
}

// Discs on walls and points (fixed: prepare() refuses moving ones), as wall_contacts: geometry
// first, a new contact inheriting the history of a lost neighbour (a wall and its end point).
template <NoTension NT, FrictionCap FC, LeverArm LA>
__attribute__((always_inline)) inline void World::onset_walls(double hs, double& worst) {
  Discs& d = discs;
  const double h = dt;
  const auto pred = [&](const std::vector<double>& v, const std::vector<double>& v0, std::size_t i) {
    return onset::predicted(v, v0, i, h);
  };
  auto& wl = neighbors.walls;
  const int n_walls = static_cast<int>(geometry.walls.size());
  char* now = touch_scratch_[0].data();
  double* dist = dist_scratch_[0].data();
  for (std::size_t b = 0; b < wl.size();) {
    std::size_t e = b;
    while (e < wl.size() && wl[e].i == wl[b].i) ++e;
    const int i = wl[b].i;
    for (std::size_t a = b; a < e; ++a) {
      WallContact& c = wl[a];
      ObstacleHit hit{};
      now[a - b] = closest_point(geometry, c.k, d.x[i], d.y[i], hit) && hit.dist <= d.r(i) && hit.dist > 0;
      if (now[a - b]) {
        dist[a - b] = hit.dist;
        c.px = hit.px; c.py = hit.py;
        const UnitNormal nrm = unit_normal(hit.px - d.x[i], hit.py - d.y[i], hit.dist);  // (4)
        c.nx = nrm.x; c.ny = nrm.y;
      }
    }
    for (std::size_t a = b; a < e; ++a) {
      if (!now[a - b] || wl[a].touching) continue;
      for (std::size_t o = b; o < e; ++o)
        if (!now[o - b] && wl[o].touching && adjacent(wl[o].k, wl[a].k)) {
          wl[a].en = wl[o].en; wl[a].es = wl[o].es; wl[a].fn = wl[o].fn;
          wl[o].en = wl[o].es = 0;
          wl[a].touching = true;  // a continued contact: no onset
        }
    }
    for (std::size_t a = b; a < e; ++a) {
      WallContact& c = wl[a];
      const bool was = c.touching;
      c.touching = now[a - b];
      if (!c.touching) { c.en = c.es = c.fn = c.fs = 0; continue; }
      const UnitNormal nrm{c.nx, c.ny};
      const double overlap = d.r(i) - dist[a - b];
      const double arm = LA == LeverArm::contact_point ? d.r(i) - 0.5 * overlap : d.r(i);
      const double ddx = d.vx[i] * hs, ddy = d.vy[i] * hs;
      const double du_n = normal_increment(ddx, ddy, nrm);
      const double du_s = shear_increment(ddx, ddy, nrm, arm * (d.omega[i] * hs));
      const double pdx = pred(d.vx, onset_vx_, i), pdy = pred(d.vy, onset_vy_, i);
      const double dash_n = normal_increment(pdx, pdy, nrm);
      const double dash_s = shear_increment(pdx, pdy, nrm, arm * pred(d.omega, onset_om_, i));
      const int km = c.k < n_walls ? geometry.walls[c.k].material : geometry.points[c.k - n_walls].material;
      const PairProps& p = props[d.material(i) * n_materials + km];
      const double cap0 = was ? onset::coulomb_cap<FC>(p, c.en, c.fn) : -1.0;
      double jn, js;
      onset::onset_contact<NT, FC>(p, overlap, du_n, du_s, dash_n, dash_s, h, cap0, c.en, c.es, c.fn, c.fs, jn, js);
      worst = std::max(worst, overlap);
      const ContactForce f = contact_force(c.fn, c.fs, nrm);  // (15)
      d.fx[i] += f.x; d.fy[i] += f.y;
      d.torque[i] -= contact_moment(arm, c.fs);
      const ContactForce J = contact_force(jn, js, nrm);
      onset_jx_[i] += J.x; onset_jy_[i] += J.y;
      onset_jt_[i] -= contact_moment(arm, js);
    }
    b = e;
  }
}

}  // namespace dem
