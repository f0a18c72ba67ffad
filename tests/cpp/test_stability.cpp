// Time-step bounds from the scheme's own step matrix against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/clusters.hpp"
#include "helpers.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"

using namespace dem;

TEST(Stability, Eq18AndVerletMatchTheDampedCentralDifferenceBound) {
  // validation.md: dt < (2 / w0) (sqrt(1 + zeta^2) - zeta) for one damped degree of freedom.
  const double m = 4.16, k = 9.45e7;
  for (double zeta : {0.0, 0.1, 0.5, 1.0015, 2.0}) {
    const double c = 2 * zeta * std::sqrt(m * k);
    const double w0 = std::sqrt(k / m);
    const double exact = 2 / w0 * (std::sqrt(1 + zeta * zeta) - zeta);
    EXPECT_NEAR(scheme_dt_bound(Scheme::paper_eq18, m, k, c), exact, 1e-6 * exact) << "zeta " << zeta;
    EXPECT_NEAR(scheme_dt_bound(Scheme::velocity_verlet, m, k, c), exact, 1e-6 * exact) << "zeta " << zeta;
  }
}

TEST(Stability, SpectralRadiusOfUndampedStepIsOneInsideTheBound) {
  const double m = 1, k = 1;
  EXPECT_NEAR(spectral_radius(Scheme::velocity_verlet, m, k, 0, 1.0), 1.0, 1e-12);
  EXPECT_GT(spectral_radius(Scheme::velocity_verlet, m, k, 0, 2.01), 1.0);
}

TEST(Stability, Eq19IsStableBeyondCentralDifferenceForThePaperContact) {
  // The paper's claim (section 2(4)): eq. (19) is more stable. For its near-critical contact
  // (zeta = 1.0015), its bound must exceed eq. (18)'s.
  const double m = 4.1625, k = 9.45e7, zeta = 1.0015, c = 2 * zeta * std::sqrt(m * k);
  EXPECT_GT(scheme_dt_bound(Scheme::paper_eq19, m, k, c), scheme_dt_bound(Scheme::paper_eq18, m, k, c));
}

TEST(Stability, TheLightestDiscOfAMaterialSetsItsBounds) {
  // Every bound grows as sqrt(m): discs of 0.4 and 0.6 cm of one material are bounded by the
  // 0.4 cm disc's modes (m* = m/2 for two of them, rotation mass m/2 for the four contacts),
  // whatever the number of larger discs beside it.
  PairProps p;  // Table 2 constants for rho g = 2.65 * 980
  const double rg = 2.65 * 980.0;
  p.kn = 3.64e4 * rg; p.ks = 0.91e4 * rg; p.eta_n = 15.3 * rg; p.eta_s = 7.65 * rg; p.mu = 0.5;
  const auto world = [&](int large) {
    World w;
    w.n_materials = 1;
    w.props = {p};
    w.scheme = Scheme::velocity_verlet;
    w.discs.add(0, 0, 0.4, 2.65, 0);
    for (int k = 0; k < large; ++k) w.discs.add(2.0 + 1.5 * k, 0, 0.6, 2.65, 0);
    return w;
  };
  const double m = 2.65 * M_PI * 0.4 * 0.4;
  const double rot = scheme_dt_bound(Scheme::velocity_verlet, m / 2, 4 * p.ks, 4 * p.eta_s);
  const double normal = scheme_dt_bound(Scheme::velocity_verlet, m / 2, p.kn, p.eta_n);
  for (int large : {1, 9}) {
    const StabilityReport rep = stability_report(world(large), {"sand"});
    ASSERT_EQ(rep.pairs.size(), 1u);
    EXPECT_DOUBLE_EQ(rep.pairs[0].m_eff, m / 2) << large << " large discs";
    EXPECT_DOUBLE_EQ(rep.pairs[0].dt_normal, normal) << large << " large discs";
    EXPECT_DOUBLE_EQ(rep.dt_rot_z4, rot) << large << " large discs";
    EXPECT_DOUBLE_EQ(rep.dt_bound, std::min(rep.dt_single, rot)) << large << " large discs";
  }
  // The 0.6 cm discs alone: their own, larger bound.
  World large = world(3);
  large.discs = Discs{};
  large.discs.add(0, 0, 0.6, 2.65, 0);
  const double m6 = 2.65 * M_PI * 0.6 * 0.6;
  const double rot6 = stability_report(large, {"sand"}).dt_rot_z4;
  EXPECT_DOUBLE_EQ(rot6, scheme_dt_bound(Scheme::velocity_verlet, m6 / 2, 4 * p.ks, 4 * p.eta_s));
  EXPECT_GT(rot6, 1.2 * rot);
}

// Paper 2's clusters: the bound of a whole bonded cluster from its step matrix.
namespace {
World two_bonded_discs(Scheme scheme, double gap_over_r) {
  PairProps p;  // paper 1's disc-disc constants (Table 2), rho g = 2.65 * 980
  const double rg = 2.65 * 980.0;
  p.kn = 3.64e4 * rg; p.ks = 0.91e4 * rg; p.eta_n = 15.3 * rg; p.eta_s = 7.65 * rg; p.mu = 0.577;
  World w;
  w.n_materials = 1;
  w.props = {p};
  w.scheme = scheme;
  w.discs.add(0, 0, 1.0, 2.65, 0);
  w.discs.add(2.0 + gap_over_r, 0, 1.0, 2.65, 0);
  ClusterSpec c;
  c.enabled = true;
  c.touch_tolerance = 2.0;  // bond across the gap
  c.members = {{0, 1}};
  w.bonds = make_bonds(w.discs, c);
  return w;
}
}  // namespace

TEST(Stability, TwoBondedDiscsAloneHaveTheModesOfOneContact) {
  // Alone, the pair's relative motion splits into a normal mode (mass m/2, K_n, eta_n) and a
  // shear mode whose discs slide and turn: the shear increment (5b) is dx_s + a_i dphi_i +
  // a_j dphi_j, so 1/m_t = 2/m + (a_i^2 + a_j^2) / I with I = m r^2 / 2 (m/6 for touching
  // discs, a = r). Its rigid motions (eigenvalue 1) must not count as unstable.
  for (Scheme s : dem::testing::kSchemes) {
    for (double gap : {0.0, 1.0}) {  // touching; bonded across a gap of r (a = 1.5 r)
      const World w = two_bonded_discs(s, gap);
      const PairProps& p = w.props[0];
      const double m = w.discs.mass(0), r = 1.0, a = r * std::max(1.0, (2.0 + gap) / 2.0);
      ASSERT_DOUBLE_EQ(w.bonds[0].ai, a);
      const double m_t = 1.0 / (2.0 / m + 2 * a * a / (m * r * r / 2));
      const double expected = std::min(scheme_dt_bound(s, m / 2, p.kn, p.eta_n), scheme_dt_bound(s, m_t, p.ks, p.eta_s));
      const ClusterBound b = cluster_dt_bound(w, s);
      EXPECT_NEAR(b.dt, expected, 2e-6 * expected) << to_string(s) << " gap " << gap;
      EXPECT_EQ(b.discs, 2);
      EXPECT_EQ(b.shapes, 1);
    }
  }
}

TEST(Stability, ABondAcrossAGapSetsTheEnforcedBound) {
  // Lever arms of 1.5 r: the shear mode's 1/m_t = 11/m is above the rotation on four contacts
  // (8/m with K_s), so the cluster sets the enforced bound; without bonds it is infinite.
  const World w = two_bonded_discs(Scheme::paper_eq19, 1.0);
  const StabilityReport rep = stability_report(w, {"sand"});
  EXPECT_LT(rep.clusters.dt, rep.dt_rot_z4);
  EXPECT_EQ(rep.dt_bound, rep.clusters.dt);
  EXPECT_NE(rep.limited_by.find("bonded cluster of 2 discs"), std::string::npos) << rep.limited_by;
  World free = w;
  free.bonds.clear();
  const StabilityReport none = stability_report(free, {"sand"});
  EXPECT_TRUE(std::isinf(none.clusters.dt));
  EXPECT_EQ(none.clusters.shapes, 0);
  EXPECT_EQ(none.dt_bound, std::min(none.dt_single, none.dt_rot_z4));
}

TEST(Stability, AHeldClusterIsStifferAndEqualShapesAreComputedOnce) {
  // Two equal bonded pairs, each resting on a wall (gap 0.005 cm): one shape; the wall's
  // springs add to the pair's, so the bound is below the pair's alone.
  World w = two_bonded_discs(Scheme::velocity_verlet, 0.0);
  const double alone = cluster_dt_bound(w, Scheme::velocity_verlet).dt;
  w.discs.add(10, 0, 1.0, 2.65, 0);
  w.discs.add(12, 0, 1.0, 2.65, 0);
  ClusterSpec c;
  c.enabled = true;
  c.members = {{0, 1}, {2, 3}};
  w.bonds = make_bonds(w.discs, c);
  w.geometry.walls.push_back({"floor", "bottom", -5, -1.005, 20, -1.005, 0});
  const ClusterBound b = cluster_dt_bound(w, Scheme::velocity_verlet);
  EXPECT_EQ(b.shapes, 1);
  EXPECT_LT(b.dt, alone);
  w.geometry.walls[0].active = false;  // a removed wall holds nothing
  EXPECT_DOUBLE_EQ(cluster_dt_bound(w, Scheme::velocity_verlet).dt, alone);
}

TEST(Stability, TheTouchDistanceDecidesWhichNeighboursHoldACluster) {
  // The wall 0.005 below the pair holds it within a touch of 0.01 (the cgs default) and not within
  // 0.0001 (the same 0.01 cm in an si scene's metres would be 1e-4 of its lengths).
  World w = two_bonded_discs(Scheme::velocity_verlet, 0.0);
  const double alone = cluster_dt_bound(w, Scheme::velocity_verlet).dt;
  w.geometry.walls.push_back({"floor", "bottom", -5, -1.005, 20, -1.005, 0});
  EXPECT_LT(cluster_dt_bound(w, Scheme::velocity_verlet, kClusterTouch).dt, alone);
  EXPECT_DOUBLE_EQ(cluster_dt_bound(w, Scheme::velocity_verlet, 1e-4).dt, alone);
}

TEST(Stability, ClustersTooLargeToExamineAreCountedNotComputed) {
  // A row of kClusterMaxDiscs + 1 touching discs bonded into one body: skipped (a step matrix of
  // 9 rows a disc, bisected a hundred times, takes seconds at 16 discs); one disc fewer is examined.
  for (int extra : {1, 0}) {
    World w = two_bonded_discs(Scheme::paper_eq19, 0.0);
    const int n = kClusterMaxDiscs + extra;
    for (int k = 2; k < n; ++k) w.discs.add(2.0 * k, 0, 1.0, 2.65, 0);
    ClusterSpec c;
    c.enabled = true;
    c.bonds = BondSet::touching;
    c.members = {{}};
    for (int k = 0; k < n; ++k) c.members[0].push_back(k);
    w.bonds = make_bonds(w.discs, c);
    const ClusterBound b = cluster_dt_bound(w, Scheme::paper_eq19);
    EXPECT_EQ(b.skipped, extra);
    EXPECT_EQ(std::isinf(b.dt), extra == 1);
    if (extra == 0) {
      EXPECT_EQ(b.discs, n);
    }
  }
}
