// Paper 2's clusters: bonded pairs act in tension and without a Coulomb cap; a cluster moves as
// one elastic body; scenes without clusters are untouched.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/clusters.hpp"
#include "helpers.hpp"
#include "physics/world.hpp"

using namespace dem;
using dem::testing::make_world;

namespace {

constexpr double kRho = 2.65, kG = 980.0;

// The paper's constants (Table 2 of paper 1 = Table 1 of paper 2): disc-disc and disc-wall.
PairProps paper_disc() {
  PairProps p;
  p.kn = 3.64e4 * kRho * kG;
  p.ks = 0.91e4 * kRho * kG;
  p.eta_n = 15.3 * kRho * kG;
  p.eta_s = 7.65 * kRho * kG;
  p.mu = 0.577;
  return p;
}
PairProps paper_wall() {
  PairProps p = paper_disc();
  p.kn *= 2; p.ks *= 2; p.eta_n *= 2; p.eta_s *= 2;
  p.mu = 0.176;
  return p;
}

// A 3-disc lattice cluster of contact angle alpha: two base discs p = 2 d cos(alpha) apart, the
// apex on top, diagonal neighbours at d = 2r (touching).
void add_cluster(World& w, double x0, double y0, double alpha_deg, double r = 1.0) {
  const double a = alpha_deg * M_PI / 180, d = 2 * r;
  w.discs.add(x0, y0, r, kRho, 0);
  w.discs.add(x0 + 2 * d * std::cos(a), y0, r, kRho, 0);
  w.discs.add(x0 + d * std::cos(a), y0 + d * std::sin(a), r, kRho, 0);
}

}  // namespace

TEST(Clusters, BondsOfAllPairsOrOfTouchingPairs) {
  World w = make_world(paper_disc(), {}, Scheme::paper_eq19, 1e-4);
  add_cluster(w, 0, 1, 50);
  ClusterSpec all;
  all.members = {{0, 1, 2}};
  const auto b_all = make_bonds(w.discs, all);
  ASSERT_EQ(b_all.size(), 3u);
  // The base pair has a gap: lever arms stretched to half the centre distance.
  const double p = 4 * std::cos(50 * M_PI / 180);
  EXPECT_EQ(b_all[0].i, 0);
  EXPECT_EQ(b_all[0].j, 1);
  EXPECT_NEAR(b_all[0].rest, p, 1e-12);
  EXPECT_NEAR(b_all[0].ai + b_all[0].aj, p, 1e-12);
  EXPECT_NEAR(b_all[1].ai, 1.0, 1e-12);  // touching pairs: a = r as in eq. (5b)
  ClusterSpec touching = all;
  touching.bonds = BondSet::touching;
  EXPECT_EQ(make_bonds(w.discs, touching).size(), 2u);  // the V: apex to both base discs
  ClusterSpec split = touching;
  split.members = {{0, 1}};  // a gap pair alone is not connected by touching pairs
  EXPECT_THROW(make_bonds(w.discs, split), std::invalid_argument);
  ClusterSpec twice = all;
  twice.members = {{0, 2}, {2, 1}};
  EXPECT_THROW(make_bonds(w.discs, twice), std::invalid_argument);
  ClusterSpec outside = all;
  outside.members = {{0, 7}};
  EXPECT_THROW(make_bonds(w.discs, outside), std::invalid_argument);
}

// A tensile pull on a bonded pair is resisted linearly without limit; on two free discs the
// contact ends at once (no tension, eq. 8). Displacements are prescribed step by step.
TEST(Clusters, TensilePullIsResistedLinearlyWithoutCapOnlyByABond) {
  const PairProps p = paper_disc();
  const double dt = 1e-4;
  for (bool bonded : {true, false}) {
    World w = make_world(p, {}, Scheme::paper_eq19, dt);  // eq. 19 keeps the increments set here
    w.discs.add(0, 0, 1, kRho, 0);
    w.discs.add(2, 0, 1, kRho, 0);  // touching
    if (bonded) {
      ClusterSpec c;
      c.members = {{0, 1}};
      w.bonds = make_bonds(w.discs, c);
    }
    w.init();
    const int n = 200;
    const double step = 0.5 / n;  // pulled apart by half a radius in all
    for (int k = 1; k <= n; ++k) {
      w.discs.x[1] += step;
      w.discs.dux[1] = step;
      w.compute_forces_now();
      const double pulled = k * step;
      if (bonded) {
        const Bond& b = w.bonds[0];
        EXPECT_NEAR(b.en, -p.kn * pulled, 1e-9 * p.kn * pulled);           // linear, tensile
        EXPECT_NEAR(b.fn, -p.kn * pulled - p.eta_n * step / dt, 1e-9 * p.kn * pulled);  // with its dashpot
        EXPECT_NEAR(w.discs.fx[1], b.fn, 1e-9 * std::abs(b.fn));  // force on j: f_n n, n = (1, 0)
        EXPECT_LT(w.discs.fx[1], 0);  // pulled back towards disc 0
      } else {
        EXPECT_EQ(w.discs.fx[1], 0);  // apart: nothing holds them
        EXPECT_EQ(w.discs.fx[0], 0);
      }
    }
  }
}

// The same for shear: a bonded pair under a small normal load carries a shear force far beyond
// mu e_n; a free pair is capped at mu e_n (eq. 13).
TEST(Clusters, BondedShearHasNoCoulombCap) {
  const PairProps p = paper_disc();
  const double dt = 1e-4;
  for (bool bonded : {true, false}) {
    World w = make_world(p, {}, Scheme::paper_eq19, dt);  // eq. 19 keeps the increments set here
    w.discs.add(0, 0, 1, kRho, 0);
    w.discs.add(1.999, 0, 1, kRho, 0);  // overlapping by 1e-3: in contact as a free pair too
    if (bonded) {
      ClusterSpec c;
      c.members = {{0, 1}};
      w.bonds = make_bonds(w.discs, c);
    }
    w.init();
    // Press by 1e-3 cm (e_n = K_n 1e-3), then slide disc 1 up by 0.01 cm in 100 steps.
    w.discs.x[1] -= 1e-3;
    w.discs.dux[1] = -1e-3;
    w.compute_forces_now();
    w.discs.dux[1] = 0;
    const double en = p.kn * 1e-3;
    const int n = 100;
    double es = 0, en_now = 0;
    for (int k = 1; k <= n; ++k) {
      w.discs.y[1] += 1e-4;
      w.discs.duy[1] = 1e-4;
      w.compute_forces_now();
      es = bonded ? w.bonds[0].es : w.neighbors.pairs[0].es;
      en_now = bonded ? w.bonds[0].en : w.neighbors.pairs[0].en;
    }
    EXPECT_NEAR(en_now, en, 5e-2 * en);  // the normal load barely changes
    // 0.01 cm of slip along t (n stays within 0.3 deg of (1, 0)): K_s 0.01 = 9.5 e_n.
    if (bonded)
      EXPECT_NEAR(std::abs(es), p.ks * 0.01, 1e-4 * p.ks * 0.01);  // far beyond mu e_n
    else
      EXPECT_NEAR(std::abs(es), p.mu * en_now, 1e-12 * en);       // capped (13a)
    EXPECT_GT(p.ks * 0.01, 3 * p.mu * en);
  }
}

// A free cluster dropped onto a wall lands and comes to rest as one body: its bonds never stretch
// or shorten by more than the energy bound sqrt(2 E / K_n) (E: the potential energy released,
// which the bonds' springs can never exceed since the rest is dissipated or kinetic), and at rest
// by no more than twice its weight over K_n; the three discs turn together.
TEST(Clusters, FallingClusterStaysIntact) {
  const PairProps p = paper_disc();
  const double dt = 5e-5;
  World w = make_world(p, {}, Scheme::paper_eq19, dt, -kG, nullptr);
  PairProps wall = paper_wall();
  w.props = {p, wall, wall, wall};
  w.geometry.walls.push_back({"floor", "bottom", -10, 0, 10, 0, 1});
  const double drop = 1.0;  // cm above touching
  add_cluster(w, -1.5, 1 + drop, 50);
  ClusterSpec c;
  c.members = {{0, 1, 2}};
  w.bonds = make_bonds(w.discs, c);
  w.rotation_angle = true;  // the discs' turns are compared below
  w.init();
  double M = 0, y0 = 0;
  for (int i = 0; i < 3; ++i) { M += w.discs.mass(i); y0 += w.discs.mass(i) * w.discs.y[i]; }
  y0 /= M;
  double worst = 0, worst_rot = 0;
  for (int k = 0; k < 20000; ++k) {  // 1 s
    w.step();
    worst = std::max(worst, max_bond_strain(w.discs, w.bonds));
    worst_rot = std::max({worst_rot, std::abs(w.discs.phi[0] - w.discs.phi[2]), std::abs(w.discs.phi[1] - w.discs.phi[2])});
  }
  double y1 = 0;
  for (int i = 0; i < 3; ++i) y1 += w.discs.mass(i) * w.discs.y[i];
  y1 /= M;
  const double E = M * kG * (y0 - y1);
  ASSERT_GT(E, 0);
  const double rest_min = 2.0;  // shortest bond (touching pairs)
  const double tol_dynamic = std::sqrt(2 * E / p.kn) / rest_min;
  EXPECT_LT(worst, tol_dynamic) << "bond strain during the fall and landing";  // about 1.1 %
  EXPECT_LT(max_bond_strain(w.discs, w.bonds), 2 * M * kG / p.kn / rest_min) << "at rest";
  // Rotations: a relative turn needs a shear deformation a dphi within the same energy bound.
  EXPECT_LT(worst_rot, std::sqrt(2 * E / p.ks) / 1.0);
  EXPECT_LT(w.kinetic_energy(), 1e-6 * E);  // at rest on the floor
  // Landed on its two base discs, which rest on the floor.
  EXPECT_NEAR(w.discs.y[0], 1.0, 1e-3);
  EXPECT_NEAR(w.discs.y[1], 1.0, 1e-3);
}

// The same three discs without bonds change shape on landing many times more than the cluster
// does: the bonds are what holds it.
TEST(Clusters, WithoutBondsTheSameDiscsChangeShape) {
  const PairProps p = paper_disc();
  double strain[2];
  for (int bonded = 0; bonded < 2; ++bonded) {
    World w = make_world(p, {}, Scheme::paper_eq19, 5e-5, -kG);
    PairProps wall = paper_wall();
    w.props = {p, wall, wall, wall};
    w.geometry.walls.push_back({"floor", "bottom", -10, 0, 10, 0, 1});
    add_cluster(w, -1.5, 2.0, 50);
    ClusterSpec c;
    c.members = {{0, 1, 2}};
    const std::vector<Bond> shape = make_bonds(w.discs, c);  // the three pairs and their distances
    if (bonded) w.bonds = shape;
    w.init();
    for (int k = 0; k < 20000; ++k) w.step();
    strain[bonded] = max_bond_strain(w.discs, shape);
  }
  EXPECT_GT(strain[0], 10 * strain[1]) << "free " << strain[0] << ", bonded " << strain[1];
}

// Scenes without clusters never enter the bond code: the lists are as before and no bond
// memory exists; a bonded pair is never a neighbour-list pair.
TEST(Clusters, BondedPairsAreNotNeighbourPairs) {
  World w = make_world(paper_disc(), {}, Scheme::paper_eq19, 1e-4);
  add_cluster(w, 0, 1, 58);
  w.discs.add(6, 1, 1, kRho, 0);
  ClusterSpec c;
  c.members = {{0, 1, 2}};
  w.bonds = make_bonds(w.discs, c);
  w.init();
  for (const PairContact& pc : w.neighbors.pairs)
    for (const Bond& b : w.bonds) EXPECT_FALSE(pc.i == b.i && pc.j == b.j);
  World plain = make_world(paper_disc(), {}, Scheme::paper_eq19, 1e-4);
  add_cluster(plain, 0, 1, 58);
  plain.init();
  EXPECT_TRUE(plain.bonds.empty());
  EXPECT_EQ(plain.neighbors.pairs.size(), 3u);
}
