#include "physics/stability.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "physics/neighbors.hpp"
#include "physics/world.hpp"

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
  } else if (scheme == Scheme::velocity_verlet_onset) {  // du: the dashpot's predicted v(t) dt (onset.cpp)
    const double v0 = v;
    v += 0.5 * dt * force(x, du) / m;
    x += v * dt;
    du = (2 * v - v0) * dt;
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

namespace {
// Spectral radius of one step of `scheme` on the linear system M x'' = -K x - C x' written the
// paper's way (as spectral_radius): minv the diagonal of M^-1.
double system_spectral_radius(Scheme scheme, const Eigen::MatrixXd& K, const Eigen::MatrixXd& C,
                              const Eigen::VectorXd& minv, double dt) {
  const Eigen::Index n = minv.size();
  const auto acc = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& du) -> Eigen::VectorXd {
    return minv.cwiseProduct(-(K * x) - C * (du / dt));
  };
  Eigen::MatrixXd A(3 * n, 3 * n);  // columns: one step of each unit state (x, v, du)
  for (Eigen::Index col = 0; col < 3 * n; ++col) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n), v = x, du = x;
    (col < n ? x : col < 2 * n ? v : du)[col % n] = 1;
    if (scheme == Scheme::velocity_verlet) {
      v += 0.5 * dt * acc(x, du);
      du = v * dt;
      x += du;
      v += 0.5 * dt * acc(x, du);
    } else if (scheme == Scheme::velocity_verlet_onset) {  // du: the dashpots' predicted v(t) dt (onset.cpp)
      const Eigen::VectorXd v0 = v;
      v += 0.5 * dt * acc(x, du);
      x += v * dt;
      du = (2 * v - v0) * dt;
      v += 0.5 * dt * acc(x, du);
    } else {
      v += dt * acc(x, du);                                                      // (17)
      du = scheme == Scheme::paper_eq18 ? Eigen::VectorXd(v * dt) : Eigen::VectorXd(0.5 * (du + v * dt));  // (18) / (19)
      x += du;
    }
    A.col(col) << x, v, du;
  }
  return Eigen::EigenSolver<Eigen::MatrixXd>(A, false).eigenvalues().cwiseAbs().maxCoeff();
}

// The linearised system of one cluster (3 degrees of freedom a disc: x, y, phi).
struct ClusterSystem {
  Eigen::MatrixXd K, C;
  Eigen::VectorXd minv;
};

// A sticking contact (or bond) between dof blocks a and b (b < 0: a fixed partner) along the unit
// normal (nx, ny) from a to b, lever arms la, lb: the relative normal and shear increments of
// (5a), (5b) are rows bn, bs; the springs and dashpots act along them.
void add_contact(ClusterSystem& s, int a, int b, double nx, double ny, double la, double lb, const PairProps& p) {
  const Eigen::Index n = s.minv.size();
  Eigen::VectorXd bn = Eigen::VectorXd::Zero(n), bs = Eigen::VectorXd::Zero(n);
  bn[3 * a] = nx; bn[3 * a + 1] = ny;
  bs[3 * a] = -ny; bs[3 * a + 1] = nx; bs[3 * a + 2] = la;
  if (b >= 0) {
    bn[3 * b] = -nx; bn[3 * b + 1] = -ny;
    bs[3 * b] = ny; bs[3 * b + 1] = -nx; bs[3 * b + 2] = lb;
  }
  s.K += p.kn * bn * bn.transpose() + p.ks * bs * bs.transpose();
  s.C += p.eta_n * bn * bn.transpose() + p.eta_s * bs * bs.transpose();
}

double system_dt_bound(Scheme scheme, const ClusterSystem& s) {
  // Start well below the highest frequency (Gershgorin: omega^2 <= max row sum of |M^-1 K|).
  double w2 = 0;
  for (Eigen::Index r = 0; r < s.K.rows(); ++r) w2 = std::max(w2, s.minv[r] * s.K.row(r).cwiseAbs().sum());
  if (!(w2 > 0)) return std::numeric_limits<double>::infinity();
  // A cluster free to move has rigid modes (eigenvalue 1, not diagonalisable: computed as 1 +
  // O(1e-8)); the tolerance keeps them stable and moves the bound by a part in a million.
  const double tol = 1e-6, w = std::sqrt(w2);
  const auto stable = [&](double dt) { return system_spectral_radius(scheme, s.K, s.C, s.minv, dt) <= 1 + tol; };
  double lo = 1e-3 / w, hi = lo;
  while (stable(hi)) {
    lo = hi;
    hi *= 1.2;
    if (hi > 100 / w) return std::numeric_limits<double>::infinity();
  }
  for (int it = 0; it < 50; ++it) {
    const double mid = 0.5 * (lo + hi);
    (stable(mid) ? lo : hi) = mid;
  }
  return lo;
}
}  // namespace

namespace {
// The clusters: the connected discs of the bonds (union-find), numbered in order of their first
// disc; each disc's cluster (-1: none) and its place in it.
struct Clusters {
  std::vector<int> cluster, local;
  std::vector<std::vector<int>> members;
};

Clusters find_clusters(const World& w) {
  const int n = static_cast<int>(w.discs.size());
  std::vector<int> root(n);
  for (int i = 0; i < n; ++i) root[i] = i;
  const auto find = [&](int i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  for (const Bond& b : w.bonds) root[find(b.i)] = find(b.j);
  Clusters c{std::vector<int>(n, -1), std::vector<int>(n, -1), {}};
  std::vector<int> number(n, -1);  // by root: -1 no bond, -2 a cluster not numbered yet
  for (const Bond& b : w.bonds) number[find(b.i)] = -2;
  for (int i = 0; i < n; ++i) {
    int& k = number[find(i)];
    if (k == -1) continue;
    if (k == -2) {
      k = static_cast<int>(c.members.size());
      c.members.emplace_back();
    }
    c.cluster[i] = k;
    c.local[i] = static_cast<int>(c.members[k].size());
    c.members[k].push_back(i);
  }
  return c;
}

// A sticking contact of a cluster.
struct Link {
  int a, b;         // places in the cluster (b < 0: a fixed partner)
  double nx, ny;    // unit normal from a to b
  double la, lb;    // lever arms
  const PairProps* p;
};

// The sticking contacts of each cluster: bonds, and the partners the engine's own lists find
// within `touch` of touching (a build with that skin), discs and obstacles.
std::vector<std::vector<Link>> cluster_links(const World& w, const Clusters& cl, double touch) {
  const Discs& d = w.discs;
  const std::vector<int>&cluster = cl.cluster, &local = cl.local;
  std::vector<std::vector<Link>> links(cl.members.size());
  for (const Bond& b : w.bonds) {
    const double dx = d.x[b.j] - d.x[b.i], dy = d.y[b.j] - d.y[b.i], R = std::hypot(dx, dy);
    if (!(R > 0)) continue;  // coincident discs (refused by the scene check): no direction
    links[cluster[b.i]].push_back({local[b.i], local[b.j], dx / R, dy / R, b.ai, b.aj,
                                   &w.pair(d.material(b.i), d.material(b.j))});
  }
  Neighbors near;
  near.skin = touch;
  near.rebuild(d, w.geometry, 1);
  const auto bonded = [&](int i, int j) {  // i < j
    return std::binary_search(w.bonds.begin(), w.bonds.end(), Bond{i, j, 0, 0, 0, 0, 0, 0, 0},
                              [](const Bond& u, const Bond& v) { return u.i != v.i ? u.i < v.i : u.j < v.j; });
  };
  for (const PairContact& c : near.pairs) {
    const int i = c.i, j = c.j;
    if ((cluster[i] < 0 && cluster[j] < 0) || bonded(i, j)) continue;
    const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i], R = std::hypot(dx, dy);
    if (!(R > 0) || R - d.r(i) - d.r(j) > touch) continue;
    const PairProps* p = &w.pair(d.material(i), d.material(j));
    const bool same = cluster[i] == cluster[j];
    if (cluster[i] >= 0) links[cluster[i]].push_back({local[i], same ? local[j] : -1, dx / R, dy / R, d.r(i), d.r(j), p});
    if (cluster[j] >= 0 && !same) links[cluster[j]].push_back({local[j], -1, -dx / R, -dy / R, d.r(j), d.r(i), p});
  }
  const int nw = static_cast<int>(w.geometry.walls.size());
  for (const WallContact& c : near.walls) {
    ObstacleHit h{};
    if (cluster[c.i] < 0 || !closest_point(w.geometry, c.k, d.x[c.i], d.y[c.i], h)) continue;
    if (!(h.dist > 0) || h.dist - d.r(c.i) > touch) continue;
    const int mat = c.k < nw ? w.geometry.walls[c.k].material : w.geometry.points[c.k - nw].material;
    links[cluster[c.i]].push_back({local[c.i], -1, (h.px - d.x[c.i]) / h.dist, (h.py - d.y[c.i]) / h.dist,
                                   d.r(c.i), 0, &w.pair(d.material(c.i), mat)});
  }
  return links;
}

// A cluster's system, identified by its shape: stiffness and damping relative to their largest
// entries, to 9 digits, and the masses (clusters of one shape have one bound).
std::vector<long long> system_shape(const ClusterSystem& s, int m) {
  std::vector<long long> shape;
  const double kmax = std::max(1.0, s.K.cwiseAbs().maxCoeff()), cmax = std::max(1.0, s.C.cwiseAbs().maxCoeff());
  shape.push_back(m);
  for (Eigen::Index a = 0; a < s.K.size(); ++a) {
    shape.push_back(std::llround(s.K.data()[a] / kmax * 1e9));
    shape.push_back(std::llround(s.C.data()[a] / cmax * 1e9));
  }
  shape.push_back(std::llround(kmax));
  shape.push_back(std::llround(cmax));
  for (Eigen::Index a = 0; a < s.minv.size(); ++a) shape.push_back(std::llround(s.minv[a] * 1e12));
  return shape;
}
}  // namespace

ClusterBound cluster_dt_bound(const World& w, Scheme scheme, double touch) {
  ClusterBound out;
  out.dt = std::numeric_limits<double>::infinity();
  if (w.bonds.empty()) return out;
  const Discs& d = w.discs;
  const Clusters cl = find_clusters(w);
  const std::vector<std::vector<Link>> links = cluster_links(w, cl, touch);
  std::map<std::vector<long long>, std::size_t> seen;  // shape -> index in systems
  std::vector<ClusterSystem> systems;
  std::vector<int> sizes;
  for (std::size_t k = 0; k < cl.members.size(); ++k) {
    const int m = static_cast<int>(cl.members[k].size());
    if (m > kClusterMaxDiscs) {  // a step matrix of 9 m rows: too large to examine
      ++out.skipped;
      continue;
    }
    ClusterSystem s{Eigen::MatrixXd::Zero(3 * m, 3 * m), Eigen::MatrixXd::Zero(3 * m, 3 * m), Eigen::VectorXd(3 * m)};
    for (int a = 0; a < m; ++a) {
      const int i = cl.members[k][a];
      s.minv.segment(3 * a, 3) << 1 / d.mass(i), 1 / d.mass(i), d.inv_inertia(i);
    }
    for (const Link& l : links[k]) add_contact(s, l.a, l.b, l.nx, l.ny, l.la, l.lb, *l.p);
    if (seen.emplace(system_shape(s, m), systems.size()).second) {
      systems.push_back(std::move(s));
      sizes.push_back(m);
    }
  }
  out.shapes = static_cast<int>(systems.size());
  for (std::size_t k = 0; k < systems.size(); ++k) {
    const double b = system_dt_bound(scheme, systems[k]);
    if (b < out.dt) {
      out.dt = b;
      out.discs = sizes[k];
    }
  }
  return out;
}

namespace {
// The pair of materials a, b (a disc-disc pair, or a disc on an obstacle of b): its one-contact
// frequencies and the schemes' bounds, for discs of masses ma, mb.
PairReport pair_report(const World& w, const std::vector<std::string>& names, int a, int b, bool disc_disc, double ma,
                       double mb) {
  PairReport r;
  r.disc_disc = disc_disc;
  r.name = names[a] + (disc_disc ? "-" : "|") + names[b];
  r.p = w.pair(a, b);
  if (r.disc_disc) {
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
  return r;
}
}  // namespace

StabilityReport stability_report(const World& w, const std::vector<std::string>& names, double cluster_touch) {
  StabilityReport rep;
  const Discs& d = w.discs;
  const int nm = w.n_materials;
  // The lightest disc of each material (infinite: no disc of it): every bound below grows with
  // the disc's mass (as sqrt(m), as m when overdamped), so a fill of several sizes is bounded by
  // its smallest discs. The mean disc's bound lets the Janssen column's small discs rattle with a
  // period of two steps (benchmarks/README.md, "Fills of several sizes").
  std::vector<double> mmin(nm, std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < d.size(); ++i) mmin[d.material(i)] = std::min(mmin[d.material(i)], d.mass(i));
  const auto present = [&](int m) { return std::isfinite(mmin[m]); };
  std::vector<bool> obstacle_mat(nm, false);
  for (const auto& wl : w.geometry.walls) obstacle_mat[wl.material] = true;
  for (const auto& p : w.geometry.points) obstacle_mat[p.material] = true;

  rep.dt_bound = std::numeric_limits<double>::infinity();
  rep.dt_rot_z4 = rep.dt_rot_z6 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < nm; ++a) {
    if (!present(a)) continue;
    const double ma = mmin[a];
    for (int b = 0; b < nm; ++b) {
      const bool disc_b = present(b) && b >= a;
      if (!disc_b && !obstacle_mat[b]) continue;
      for (int kind = 0; kind < 2; ++kind) {  // 0: disc-disc, 1: disc-obstacle
        if (kind == 0 && !disc_b) continue;
        if (kind == 1 && !obstacle_mat[b]) continue;
        PairReport r = pair_report(w, names, a, b, kind == 0, ma, mmin[b]);
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
  // Paper 2's clusters: their bonds (across a gap, long lever arms) raise the frequencies of the
  // rotation modes above the one-contact ones.
  rep.clusters = cluster_dt_bound(w, w.scheme, cluster_touch);
  if (rep.clusters.dt < rep.dt_bound) {
    rep.dt_bound = rep.clusters.dt;
    rep.limited_by = "a bonded cluster of " + std::to_string(rep.clusters.discs) +
                     " discs with its touching neighbours held (every contact sticking)";
  }
  return rep;
}

}  // namespace dem
