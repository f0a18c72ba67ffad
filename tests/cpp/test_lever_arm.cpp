// contact.lever_arm = contact_point: the shear force acts, and a disc's rotation moves the
// contact, at a = r - overlap/2 from the centre (the middle of the overlap) instead of r, in the
// increment (5b) and the torque (15c). One contact, the first force pass from a spinning state
// (eq. 18: the increments are v dt, omega dt; the history starts at 0), against the law written
// out by hand: du_s = (-du_x n_y + du_y n_x) + (a_i omega_i + a_j omega_j) dt, e_s = K_s du_s,
// f_s = e_s + eta_s du_s / dt, torque_i = -a_i f_s, torque_j = -a_j f_s.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"

using namespace dem;
using namespace dem::testing;

namespace {

constexpr double kDt = 1e-4, kOverlap = 0.02;
constexpr double kKn = 1e7, kKs = 4e6, kEtaS = 500.0, kMu = 10.0;  // mu large: no sliding

ContactOptions contact_point() {
  ContactOptions o{NormalSpring::overlap, NoTension::total, FrictionCap::total};
  o.lever_arm = LeverArm::contact_point;
  return o;
}

World one_contact_world() {
  PairProps p;
  p.kn = kKn;
  p.ks = kKs;
  p.eta_s = kEtaS;
  p.mu = kMu;
  return make_world(p, contact_point(), Scheme::paper_eq18, kDt);
}

bool near(double got, double want) { return std::abs(got - want) <= 1e-12 * std::abs(want); }

// Two discs of radii ri, rj overlapping by kOverlap along x, spinning, disc i also moving.
void check_pair(double ri, double rj) {
  World w = one_contact_world();
  const double wi = 3.0, wj = -1.5, vx = 0.4, vy = 0.7;
  w.discs.add(0.0, 0.0, ri, 2.65, 0);
  w.discs.add(ri + rj - kOverlap, 0.0, rj, 2.65, 0);
  w.discs.vx[0] = vx;
  w.discs.vy[0] = vy;
  w.discs.omega[0] = wi;
  w.discs.omega[1] = wj;
  w.init();
  const double ai = ri - kOverlap / 2, aj = rj - kOverlap / 2;
  // n = (1, 0) from i to j: the tangential relative increment is du_y.
  const double du_s = vy * kDt + (ai * wi + aj * wj) * kDt;
  const double fs = kKs * du_s + kEtaS * du_s / kDt;
  ASSERT_EQ(w.neighbors.pairs.size(), 1u);
  EXPECT_TRUE(near(w.neighbors.pairs[0].es, kKs * du_s)) << w.neighbors.pairs[0].es << " vs " << kKs * du_s;
  EXPECT_TRUE(near(w.discs.torque[0], -ai * fs)) << w.discs.torque[0] << " vs " << -ai * fs;
  EXPECT_TRUE(near(w.discs.torque[1], -aj * fs)) << w.discs.torque[1] << " vs " << -aj * fs;
  EXPECT_TRUE(near(w.discs.fy[0], -fs)) << "(15b): f_s along -y on i";
  EXPECT_TRUE(near(w.discs.fx[0], -kKn * kOverlap)) << "the normal force does not change";
}

// One disc touching an obstacle (wall or point) whose closest point lies in direction
// theta from the centre, at distance r - kOverlap.
void check_obstacle(World& w, double r, double theta) {
  const double wi = 4.0, vx = 0.5, vy = -0.3;
  w.discs.add(0.0, 0.0, r, 2.65, 0);
  w.discs.vx[0] = vx;
  w.discs.vy[0] = vy;
  w.discs.omega[0] = wi;
  w.init();
  const double nx = std::cos(theta), ny = std::sin(theta), a = r - kOverlap / 2;
  const double du_s = (-vx * ny + vy * nx) * kDt + a * wi * kDt;
  const double fs = kKs * du_s + kEtaS * du_s / kDt;
  ASSERT_EQ(w.neighbors.walls.size(), 1u);
  EXPECT_TRUE(near(w.neighbors.walls[0].es, kKs * du_s)) << w.neighbors.walls[0].es << " vs " << kKs * du_s;
  EXPECT_TRUE(near(w.discs.torque[0], -a * fs)) << w.discs.torque[0] << " vs " << -a * fs;
}

}  // namespace

TEST(LeverArm, PairOfOneKindActsAtTheMiddleOfTheOverlap) { check_pair(1.0, 1.0); }

TEST(LeverArm, PairOfTwoKindsActsAtTheMiddleOfTheOverlap) { check_pair(1.0, 0.6); }

TEST(LeverArm, WallContactActsAtTheMiddleOfTheOverlap) {
  World w = one_contact_world();
  const double r = 1.0;
  w.geometry.walls.push_back({"floor", "bottom", -10.0, -(r - kOverlap), 10.0, -(r - kOverlap), 1});
  check_obstacle(w, r, -M_PI / 2);
}

TEST(LeverArm, PointContactActsAtTheMiddleOfTheOverlap) {
  World w = one_contact_world();
  const double r = 0.8, theta = -M_PI / 3;
  w.geometry.points.push_back({"end", "bottom", (r - kOverlap) * std::cos(theta), (r - kOverlap) * std::sin(theta), 1, {}});
  check_obstacle(w, r, theta);
}

// A shear-free scene runs the radius kernel: the option changes nothing there.
TEST(LeverArm, ShearFreeSceneIsUnchanged) {
  PairProps p;
  p.kn = kKn;
  World a = make_world(p, contact_point(), Scheme::paper_eq18, kDt);
  World b = make_world(p, ContactOptions{NormalSpring::overlap, NoTension::total, FrictionCap::total}, Scheme::paper_eq18, kDt);
  for (World* w : {&a, &b}) {
    w->discs.add(0.0, 0.0, 1.0, 2.65, 0);
    w->discs.add(2.0 - kOverlap, 0.1, 1.0, 2.65, 0);
    w->discs.omega[0] = 3.0;
    w->init();
    for (int s = 0; s < 10; ++s) w->step();
  }
  EXPECT_EQ(a.discs.x[1], b.discs.x[1]);
  EXPECT_EQ(a.discs.omega[0], b.discs.omega[0]);
}
