// Derived quantities of the contact law and time-step bounds, printed in every run's header.
#pragma once

#include <string>
#include <vector>

#include "physics/model.hpp"

namespace dem {

class World;

// Spectral radius of one step of `scheme` on the one-degree-of-freedom contact
// m x'' = -k x - c x' written the paper's way (spring on the summed increments, dashpot on the
// last increment over dt). The step is linear, so its matrix is found by stepping unit states.
double spectral_radius(Scheme scheme, double m, double k, double c, double dt);

// Largest dt for which that step is stable (spectral radius <= 1).
double scheme_dt_bound(Scheme scheme, double m, double k, double c);

struct PairReport {
  std::string name;          // e.g. "sand-sand", "sand-wall"
  bool disc_disc = true;
  // Of the lightest disc of each material (the fastest modes): m_i m_j / (m_i + m_j), or m_i
  // against an obstacle.
  double m_eff = 0;
  double m_t = 0;            // tangential effective mass (rotation included): m/6 or m/3
  PairProps p;
  double omega0 = 0, zeta_n = 0;  // sqrt(k_n/m*), eta_n / (2 sqrt(m* k_n))
  double t_contact = 0;      // pi / omega_d; infinite when overdamped (zeta_n >= 1)
  double restitution = 0;    // exp(-pi zeta / sqrt(1 - zeta^2)); 0 when overdamped
  double omega_t = 0, zeta_t = 0;
  double dt_normal = 0;      // scheme bound, normal contact
  double dt_tangential = 0;  // scheme bound, sticking shear contact
  double dt_eq26 = 0;        // paper (26): eta_n / K_n
  double dt_eq21 = 0;        // Cundall (21): 2 sqrt(m* / K_n)
  double dt_rot_z4 = 0;      // disc rotation held by 4 sticking contacts of this pair
  double dt_rot_z6 = 0;      // ... by 6 (hexagonal packing)
};

// Paper 2's clusters: the largest dt at which one step of `scheme` is stable on a whole cluster,
// linearised with every contact sticking: its discs' x, y and rotation (3 degrees of freedom a
// disc), its bonds (lever arms a_i, a_j), and the contacts to the discs, walls and points within
// kClusterTouch of touching (found by a list build with that skin), those partners held fixed
// (dem.compare.cases.shear_stability, the same in numpy, leaves points out: the shear box has none). The smallest over the distinct cluster
// shapes (clusters with the same stiffness, damping and masses are computed once). The
// many-degree-of-freedom form of the one-contact bounds above: bonds across a gap (lever arms
// R0/2 > r) stiffen the coupled rotation modes. Like them, not a bound for the whole assembly
// (moving neighbours can raise the frequencies). Infinite without bonds.
constexpr double kClusterTouch = 0.01;  // [cm] default touch: a neighbour this near holds the cluster (lattice gaps: 0.004 cm)
constexpr int kClusterMaxDiscs = 10;    // larger clusters are not examined (counted in `skipped`)
struct ClusterBound {
  double dt = 0;       // [s] the smallest bound; infinite without bonds
  int discs = 0;       // discs of the cluster that sets it
  int shapes = 0;      // distinct cluster shapes examined
  int skipped = 0;     // clusters of more than kClusterMaxDiscs discs, not examined
};
// touch: [length] a neighbour within it of touching holds the cluster (kClusterTouch in cm; the
// scene's units give it in theirs: default_length).
ClusterBound cluster_dt_bound(const World& w, Scheme scheme, double touch = kClusterTouch);

struct StabilityReport {
  std::vector<PairReport> pairs;
  double dt_single = 0;      // min over pairs of the single-contact scheme bounds
  double dt_rot_z4 = 0;      // rotation held by 4 sticking contacts, disc-disc or disc-wall constants
  bool rot_z4_at_wall = false;  // ... the lowest with a wall among the four
  double dt_rot_z6 = 0;      // ... by 6 (hexagonal packing; printed as a warning only)
  ClusterBound clusters;     // bonded clusters (paper 2); dt infinite without bonds
  double dt_bound = 0;       // enforced: min(dt_single, dt_rot_z4, clusters.dt)
  std::string limited_by;
};

StabilityReport stability_report(const World& w, const std::vector<std::string>& material_names,
                                 double cluster_touch = kClusterTouch);

}  // namespace dem
