// Paper 2's stresses on virtual horizontal planes, on a hand-made configuration whose contact
// forces are set by hand (no time step), against sums done here.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"
#include "physics/stress_planes.hpp"

using namespace dem;

TEST(StressPlanes, HandMadeForcesAcrossTwoPlanes) {
  PairProps p;
  p.kn = 1;
  World w = dem::testing::make_world(p, {}, Scheme::paper_eq19, 1e-4, -980.0);
  // Two discs below (y = 0), one on them (touching both), one above it (touching), radius 1.
  w.discs.add(0.0, 0.0, 1, 2.0, 0);
  w.discs.add(2.4, 0.0, 1, 2.0, 0);
  w.discs.add(1.2, 1.6, 1, 2.0, 0);
  w.discs.add(1.2, 3.6, 1, 2.0, 0);
  // Contacts 0-2 and 1-2 (normal from i to j: (0.6, 0.8) and (-0.6, 0.8)), a bond 2-3 in tension
  // (n = (0, 1)), a bond 0-1 lying in the bottom row, a plate contact on disc 3 (n = (0, 1)).
  w.neighbors.pairs = {PairContact{0, 2}, PairContact{1, 2}};
  w.pair_totals.assign({PairForce{0, 2, 100.0, 10.0}, PairForce{1, 2, 80.0, -5.0}});  // as a recorded pass
  w.pair_forces_step = w.steps;
  Bond b23;
  b23.i = 2; b23.j = 3; b23.fn = -30.0; b23.fs = 4.0;
  Bond b01;
  b01.i = 0; b01.j = 1; b01.fn = 7.0; b01.fs = 1.0;
  w.bonds = {b01, b23};
  WallContact plate{};
  plate.i = 3; plate.k = 0; plate.touching = true; plate.fn = 50.0; plate.fs = 2.0; plate.nx = 0; plate.ny = 1;
  w.neighbors.walls = {plate};
  // Force on j of a pair: f_n n + f_s t, t = (-ny, nx); on i the opposite.
  auto on_j = [](double fn, double fs, double nx, double ny, double& fx, double& fy) {
    fx = fn * nx - fs * ny;
    fy = fn * ny + fs * nx;
  };
  double f02x, f02y, f12x, f12y, f23x, f23y, f01x, f01y;
  on_j(100, 10, 0.6, 0.8, f02x, f02y);
  on_j(80, -5, -0.6, 0.8, f12x, f12y);
  on_j(-30, 4, 0, 1, f23x, f23y);
  on_j(7, 1, 1, 0, f01x, f01y);
  // Resultants (eq. 15 with gravity) as a force computation would leave them.
  const double g = -980.0;
  const double wx = -(50.0 * 0 - 2.0 * 1), wy = -(50.0 * 1 + 2.0 * 0);  // plate on disc 3
  w.discs.fx = {-f02x - f01x, -f12x + f01x, f02x + f12x - f23x, f23x + wx};
  w.discs.fy = {w.discs.mass(0) * g - f02y - f01y, w.discs.mass(1) * g - f12y + f01y,
                w.discs.mass(2) * g + f02y + f12y - f23y, w.discs.mass(3) * g + f23y + wy};

  int rows = 0;
  const std::vector<int> row = assign_rows(w.discs, 0.5, rows);
  ASSERT_EQ(rows, 3);
  EXPECT_EQ(row, (std::vector<int>{0, 0, 1, 2}));
  const std::vector<double> ys = planes_between_rows(w.discs, row, rows);
  ASSERT_EQ(ys.size(), 2u);
  EXPECT_DOUBLE_EQ(ys[0], 0.8);
  EXPECT_DOUBLE_EQ(ys[1], 2.6);

  const double b = 4.0;
  const auto ps = plane_stresses(w, ys, b);
  // Plane 0.8 cuts 0-2 and 1-2: the part above (disc 2) acts on discs 0 and 1 by -f_on_j.
  EXPECT_EQ(ps[0].contacts, 2);
  EXPECT_NEAR(ps[0].fx, -f02x - f12x, 1e-12);
  EXPECT_NEAR(ps[0].fy, -f02y - f12y, 1e-12);
  EXPECT_NEAR(ps[0].sigma, (f02y + f12y) / b, 1e-12);  // compression positive
  EXPECT_NEAR(ps[0].tau, (-f02x - f12x) / b, 1e-12);
  // Plane 2.6 cuts the bond 2-3 only: a tensile bond pulls the part below up (sigma < 0).
  EXPECT_EQ(ps[1].contacts, 1);
  EXPECT_NEAR(ps[1].sigma, f23y / b, 1e-12);
  EXPECT_LT(ps[1].sigma, 0);
  EXPECT_NEAR(ps[1].tau, -f23x / b, 1e-12);
  // The part above plane 2.6 is disc 3: weight and plate; the cut equals check + inertia.
  EXPECT_NEAR(ps[1].sigma_check, -(w.discs.mass(3) * g + wy) / b, 1e-12);
  EXPECT_NEAR(ps[1].tau_check, wx / b, 1e-12);
  for (const PlaneStress& q : ps) {
    EXPECT_NEAR(q.sigma, q.sigma_check + q.sigma_inertia, 1e-9);
    EXPECT_NEAR(q.tau, q.tau_check + q.tau_inertia, 1e-9);
  }
  // A pair that does not touch carries nothing across a plane.
  w.discs.y[2] = 1.7;
  const auto apart = plane_stresses(w, {0.8}, b);
  EXPECT_EQ(apart[0].contacts, 0);
}
