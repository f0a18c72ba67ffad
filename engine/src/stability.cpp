#include "stability.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "world.hpp"

namespace dem {

namespace {
// One step of the scheme on state s = (x, v, du) of the 1-DOF contact. du is the last
// increment; the force is -k x - c du/dt as in eqs. (6)-(9) without clamping.
Eigen::Vector3d one_step(Scheme scheme, double m, double k, double c, double dt, Eigen::Vector3d s) {
  double x = s[0], v = s[1], du = s[2];
  auto force = [&](double xx, double dd) { return -k * xx - c * dd / dt; };
  if (scheme == Scheme::velocity_verlet) {
    v += 0.5 * dt * force(x, du) / m;
    du = v * dt;
    x += du;
    v += 0.5 * dt * force(x, du) / m;
  } else {
    v += dt * force(x, du) / m;                                                  // (17)
    du = scheme == Scheme::paper_eq18 ? v * dt : 0.5 * (du + v * dt);            // (18) / (19)
    x += du;
  }
  return {x, v, du};
}
}  // namespace

double spectral_radius(Scheme scheme, double m, double k, double c, double dt) {
  Eigen::Matrix3d A;
  for (int col = 0; col < 3; ++col) A.col(col) = one_step(scheme, m, k, c, dt, Eigen::Vector3d::Unit(col));
  return A.eigenvalues().cwiseAbs().maxCoeff();
}

double scheme_dt_bound(Scheme scheme, double m, double k, double c) {
  const double w = std::sqrt(k / m);
  const double tol = 1e-12;
  double lo = 1e-4 / w, hi = lo;
  while (spectral_radius(scheme, m, k, c, hi) <= 1 + tol) {
    lo = hi;
    hi *= 1.05;
    if (hi > 100 / w) return std::numeric_limits<double>::infinity();
  }
  for (int it = 0; it < 80; ++it) {
    const double mid = 0.5 * (lo + hi);
    (spectral_radius(scheme, m, k, c, mid) <= 1 + tol ? lo : hi) = mid;
  }
  return lo;
}

StabilityReport stability_report(const World& w, const std::vector<std::string>& names) {
  StabilityReport rep;
  const Discs& d = w.discs;
  const int nm = w.n_materials;
  // Mean disc mass per material present among the discs.
  std::vector<double> msum(nm, 0), cnt(nm, 0);
  for (std::size_t i = 0; i < d.size(); ++i) { msum[d.material(i)] += d.mass(i); cnt[d.material(i)] += 1; }
  std::vector<bool> obstacle_mat(nm, false);
  for (const auto& wl : w.geometry.walls) obstacle_mat[wl.material] = true;
  for (const auto& p : w.geometry.points) obstacle_mat[p.material] = true;

  rep.dt_bound = std::numeric_limits<double>::infinity();
  rep.dt_rot_z4 = rep.dt_rot_z6 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < nm; ++a) {
    if (cnt[a] == 0) continue;
    const double ma = msum[a] / cnt[a];
    for (int b = 0; b < nm; ++b) {
      const bool disc_b = cnt[b] > 0 && b >= a;
      if (!disc_b && !obstacle_mat[b]) continue;
      for (int kind = 0; kind < 2; ++kind) {  // 0: disc-disc, 1: disc-obstacle
        if (kind == 0 && !disc_b) continue;
        if (kind == 1 && !obstacle_mat[b]) continue;
        PairReport r;
        r.disc_disc = kind == 0;
        r.name = names[a] + (kind == 0 ? "-" : "|") + names[b];
        r.p = w.pair(a, b);
        if (r.disc_disc) {
          const double mb = msum[b] / cnt[b];
          r.m_eff = ma * mb / (ma + mb);
          r.m_t = 1.0 / (3.0 / ma + 3.0 / mb);  // 1/m + r^2/I = 3/m per disc
        } else {
          r.m_eff = ma;
          r.m_t = ma / 3.0;
        }
        r.omega0 = std::sqrt(r.p.kn / r.m_eff);
        r.zeta_n = r.p.eta_n / (2 * std::sqrt(r.m_eff * r.p.kn));
        if (r.zeta_n < 1) {
          const double wd = r.omega0 * std::sqrt(1 - r.zeta_n * r.zeta_n);
          r.t_contact = M_PI / wd;
          r.restitution = std::exp(-M_PI * r.zeta_n / std::sqrt(1 - r.zeta_n * r.zeta_n));
        } else {
          r.t_contact = std::numeric_limits<double>::infinity();
          r.restitution = 0;
        }
        r.omega_t = r.p.ks > 0 ? std::sqrt(r.p.ks / r.m_t) : 0;
        r.zeta_t = r.p.ks > 0 ? r.p.eta_s / (2 * std::sqrt(r.m_t * r.p.ks)) : 0;
        r.dt_normal = scheme_dt_bound(w.scheme, r.m_eff, r.p.kn, r.p.eta_n);
        r.dt_tangential = r.p.ks > 0 ? scheme_dt_bound(w.scheme, r.m_t, r.p.ks, r.p.eta_s)
                                     : std::numeric_limits<double>::infinity();
        r.dt_eq26 = r.p.eta_n / r.p.kn;
        r.dt_eq21 = 2 * std::sqrt(r.m_eff / r.p.kn);
        // Rotation I phi'' = -z r^2 (K_s phi + eta_s phi'): mass I / r^2 = m / 2.
        if (r.p.ks > 0) {
          r.dt_rot_z4 = scheme_dt_bound(w.scheme, ma / 2, 4 * r.p.ks, 4 * r.p.eta_s);
          r.dt_rot_z6 = scheme_dt_bound(w.scheme, ma / 2, 6 * r.p.ks, 6 * r.p.eta_s);
        } else {
          r.dt_rot_z4 = r.dt_rot_z6 = std::numeric_limits<double>::infinity();
        }
        const double bound = std::min(r.dt_normal, r.dt_tangential);
        if (bound < rep.dt_bound) {
          rep.dt_bound = bound;
          rep.limited_by = r.name + (r.dt_normal <= r.dt_tangential ? " normal" : " tangential");
        }
        if (r.disc_disc) {
          rep.dt_rot_z4 = std::min(rep.dt_rot_z4, r.dt_rot_z4);
          rep.dt_rot_z6 = std::min(rep.dt_rot_z6, r.dt_rot_z6);
        } else {
          // The same rotation mode with the wall pair's (stiffer) constants. The stability study
          // (benchmarks/stability_study.py) finds the largest dt at which the paper's silos come
          // to rest at this bound (measured / bound 0.8-1.0 for eq. 18, eq. 19 and Verlet, and for
          // K_s/K_n = 0.1-1), not at the disc-disc one (about twice as large): between the two a
          // fill rattles for ever without blowing up. So it is enforced too.
          if (r.dt_rot_z4 < rep.dt_rot_z4) {
            rep.dt_rot_z4 = r.dt_rot_z4;
            rep.rot_z4_at_wall = true;
          }
        }
        rep.pairs.push_back(r);
      }
    }
  }
  rep.dt_single = rep.dt_bound;
  // The paper's lattices give each disc four neighbours; several shear dashpots on one rotation
  // are what blows up first (reference-codes.md), so the enforced bound includes that mode.
  if (rep.dt_rot_z4 < rep.dt_bound) {
    rep.dt_bound = rep.dt_rot_z4;
    rep.limited_by = rep.rot_z4_at_wall ? "rotation held by 4 sticking contacts with the disc-wall constants"
                                        : "rotation held by 4 sticking disc-disc contacts";
  }
  return rep;
}

}  // namespace dem
