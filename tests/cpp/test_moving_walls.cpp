// Moving walls (the shear box): a wall's motion enters the contact increments, prescribed
// rotations are exact, the plate is a rigid body integrated by the discs' scheme.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"
#include "physics/world.hpp"

using namespace dem;
using dem::testing::make_world;

namespace {

PairProps props() {
  PairProps p;
  p.kn = 1e8;
  p.ks = 2.5e7;
  p.eta_n = 4e4;
  p.eta_s = 2e4;
  p.mu = 0.5;
  return p;
}

// A vertical wall x = 0 from (0, H) down to its pivot (0, 0), rotating at omega.
void add_rotating_wall(World& w, double H, double omega) {
  w.geometry.walls.push_back({"left", "side_left", 0, H, 0, 0, 1});
  RotatingWall r;
  r.wall = static_cast<int>(w.geometry.walls.size()) - 1;
  r.ax0 = 0; r.ay0 = H; r.bx0 = 0; r.by0 = 0;
  r.pivot_x = 0; r.pivot_y = 0;
  r.reach = H;
  r.omega = omega;
  w.moving.rotating.push_back(r);
  w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
  w.moving.motion[r.wall].pivot_x = 0;
  w.moving.motion[r.wall].pivot_y = 0;
}

}  // namespace

TEST(MovingWalls, PrescribedRotationIsExact) {
  World w = make_world(props(), {}, Scheme::paper_eq19, 1e-4);
  w.discs.add(5, 5, 1, 2.65, 0);  // far from the wall
  add_rotating_wall(w, 30, -0.05);
  w.init();
  const int n = 10000;
  for (int k = 0; k < n; ++k) w.step();
  const double th = -0.05 * 1e-4 * n;
  const Wall& wl = w.geometry.walls[0];
  EXPECT_NEAR(wl.ax, -30 * std::sin(th), 1e-12);
  EXPECT_NEAR(wl.ay, 30 * std::cos(th), 1e-12);
  EXPECT_EQ(wl.bx, 0);
  EXPECT_EQ(wl.by, 0);
  EXPECT_NEAR(w.moving.motion[0].dtheta, -0.05 * 1e-4, 1e-18);
}

// One step of the wall turning towards a touching disc at height L: the contact point moves
// by L dtheta along the wall's normal (an approach) and not along it, so e_n = K_n L dtheta and
// e_s = 0; the force on the wall is the opposite of the force on the disc.
TEST(MovingWalls, WallMotionEntersTheContactIncrements) {
  const PairProps p = props();
  for (Scheme scheme : dem::testing::kSchemes) {
    World w = make_world(p, {}, scheme, 1e-4);
    const double L = 10, r = 1;
    w.discs.add(r, L, r, 2.65, 0);  // touching the wall x = 0 at height L
    add_rotating_wall(w, 30, -0.05);  // clockwise: the wall leans to +X, onto the disc
    w.init();
    w.discs.hold(0);  // only the wall moves
    // Eqs. 18/19 compute forces before they move: the wall's first turn is seen by the second
    // step's force computation; Verlet moves first.
    w.step();
    if (scheme != Scheme::velocity_verlet) w.step();
    const WallContact& c = w.neighbors.walls.at(0);
    ASSERT_TRUE(c.touching);
    const double dth = 0.05 * 1e-4;
    EXPECT_NEAR(c.en, p.kn * L * dth, 1e-6 * p.kn * L * dth) << to_string(scheme);
    EXPECT_NEAR(c.es, 0.0, 1e-6 * p.kn * L * dth) << to_string(scheme);
    const ObstacleMotion& m = w.moving.motion[0];
    EXPECT_NEAR(m.fx, -w.discs.fx[0], 1e-9 * std::abs(m.fx));
    EXPECT_NEAR(m.moment, c.py * -m.fx, 1e-6 * std::abs(m.moment));  // about the pivot (0, 0)
  }
}

// A plate and a disc resting on it, both starting at rest and touching: they fall together.
// The plate's own displacement enters the increments, so the contact sees no approach and both
// follow the scheme's free fall exactly (eq. 18: y_n = y_0 - g dt^2 n (n + 1) / 2).
TEST(MovingWalls, PlateAndDiscFallTogether) {
  const double dt = 1e-4, g = 980;
  World w = make_world(props(), {}, Scheme::paper_eq18, dt, -g);
  w.discs.add(0, 1, 1, 2.65, 0);
  w.geometry.walls.push_back({"plate", "plate", -5, 0, 5, 0, 1});
  RigidPlate p;
  p.wall = 0;
  p.mass = 100;
  p.ax0 = -5; p.ay0 = 0; p.bx0 = 5; p.by0 = 0;
  w.moving.plates.push_back(p);
  w.init();
  const int n = 1000;
  for (int k = 0; k < n; ++k) w.step();
  const double fall = g * dt * dt * n * (n + 1) / 2;
  EXPECT_NEAR(w.discs.y[0], 1 - fall, 1e-12);
  EXPECT_NEAR(w.moving.plates[0].y, -fall, 1e-12);
  EXPECT_NEAR(w.geometry.walls[0].ay, -fall, 1e-12);
  EXPECT_EQ(w.neighbors.walls.at(0).en, 0);
}

// The plate carries a disc under gravity: at rest the plate's weight plus the disc's are held by
// the floor below... here by nothing, so instead: a plate pressed on a disc lying on a fixed
// floor comes to rest with the disc carrying the plate's weight.
TEST(MovingWalls, PlateWeightIsCarried) {
  const double dt = 1e-4, g = 980;
  World w = make_world(props(), {}, Scheme::paper_eq19, dt, -g);
  w.discs.add(0, 1, 1, 2.65, 0);
  w.geometry.walls.push_back({"floor", "bottom", -5, 0, 5, 0, 1});
  w.geometry.walls.push_back({"plate", "plate", -5, 2.001, 5, 2.001, 1});
  RigidPlate p;
  p.wall = 1;
  p.mass = 50;
  p.ax0 = -5; p.ay0 = 2.001; p.bx0 = 5; p.by0 = 2.001;
  w.moving.plates.push_back(p);
  w.init();
  for (int k = 0; k < 20000; ++k) w.step();
  const ObstacleMotion& m = w.moving.motion[1];
  EXPECT_NEAR(m.fy, p.mass * g, 1e-6 * p.mass * g);  // discs push the plate up by its weight
  EXPECT_NEAR(w.moving.motion[0].fy, -(p.mass + w.discs.mass(0)) * g, 1e-6 * p.mass * g);
  EXPECT_NEAR(w.moving.plates[0].vy, 0, 1e-9);
}

// With follow set, the plate keeps the rotating wall's horizontal offset at its height.
TEST(MovingWalls, PlateFollowingTheWalls) {
  World w = make_world(props(), {}, Scheme::paper_eq19, 1e-4, 0.0);
  w.discs.add(20, 5, 1, 2.65, 0);
  add_rotating_wall(w, 30, -0.05);
  w.geometry.walls.push_back({"plate", "plate", -2, 12, 42, 12, 1});
  w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
  RigidPlate p;
  p.wall = 1;
  p.mass = 10;
  p.ax0 = -2; p.ay0 = 12; p.bx0 = 42; p.by0 = 12;
  p.follow = 0;
  w.moving.plates.push_back(p);
  w.init();
  for (int k = 0; k < 5000; ++k) w.step();
  const double th = -0.05 * 1e-4 * 5000;
  EXPECT_NEAR(w.moving.plates[0].x, -12 * std::tan(th), 1e-12);
  EXPECT_NEAR(w.moving.plates[0].y, 0, 1e-15);
}

namespace {
// A floor from (-5, 0) to (5, 0) lowered at v from t_from to t_until (a scene's walls[].velocity).
void add_lowered_floor(World& w, double v, double t_from, double t_until) {
  w.geometry.walls.push_back({"floor", "bottom", -5, 0, 5, 0, 1});
  TranslatingWall q;
  q.wall = static_cast<int>(w.geometry.walls.size()) - 1;
  q.vy = -v;
  q.t_from = t_from;
  q.t_until = t_until;
  q.ax0 = -5; q.ay0 = 0; q.bx0 = 5; q.by0 = 0;
  w.moving.translating.push_back(q);
  w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
}
}  // namespace

// A prescribed translation moves the wall by v x (the part of each step inside the window),
// whatever the scheme: nothing before move_from, exactly v (t_until - t_from) after move_until,
// and the last step's displacement is what the contact law sees.
TEST(MovingWalls, PrescribedTranslationIsExact) {
  for (Scheme scheme : dem::testing::kSchemes) {
    const double dt = 1e-4;
    World w = make_world(props(), {}, scheme, dt, 0.0);
    w.discs.add(0, 5, 1, 2.65, 0);  // far from the floor
    add_lowered_floor(w, 2.0, 0.01, 0.03);   // steps 100 .. 300
    w.init();
    for (int k = 0; k < 100; ++k) w.step();
    EXPECT_EQ(w.geometry.walls[0].ay, 0) << to_string(scheme);
    w.step();
    EXPECT_NEAR(w.moving.motion[0].duy, -2.0 * dt, 1e-15) << to_string(scheme);
    for (int k = 0; k < 399; ++k) w.step();
    EXPECT_NEAR(w.geometry.walls[0].ay, -2.0 * 0.02, 1e-12) << to_string(scheme);
    EXPECT_NEAR(w.geometry.walls[0].by, -2.0 * 0.02, 1e-12) << to_string(scheme);
    EXPECT_EQ(w.geometry.walls[0].ax, -5);
    EXPECT_EQ(w.moving.motion[0].duy, 0) << to_string(scheme);  // stopped: no increment
    EXPECT_EQ(w.moving.translations_end(), 0.03);
  }
}

// A disc settling on a floor that is lowered slowly follows it down and comes to rest on it
// again: its centre ends v (t_until - t_from) lower than where it would rest on the unmoved
// floor, with the overlap m g / kn of its weight.
TEST(MovingWalls, DiscFollowsALoweredFloor) {
  const double dt = 1e-5, g = 980;
  World w = make_world(props(), {}, Scheme::velocity_verlet, dt, -g);
  const double m = 2.65 * M_PI;                 // r = 1
  const double rest = 1 - m * g / props().kn;   // touching at the start, then the weight's overlap
  w.discs.add(0, 1, 1, 2.65, 0);
  add_lowered_floor(w, 0.5, 0.02, 0.06);        // 0.02 cm down at 0.5 cm/s
  w.init();
  for (int k = 0; k < 20000; ++k) w.step();     // 0.2 s: the floor stopped 0.14 s ago
  EXPECT_NEAR(w.geometry.walls[0].ay, -0.02, 1e-12);
  EXPECT_NEAR(w.discs.y[0], rest - 0.02, 1e-6);
  EXPECT_NEAR(w.discs.vy[0], 0, 1e-4);
}

// A state saved mid-way restores the translating wall where the clock says.
TEST(MovingWalls, TranslatingWallIsPlacedByTheClock) {
  World w = make_world(props(), {}, Scheme::velocity_verlet, 1e-4, 0.0);
  w.discs.add(0, 5, 1, 2.65, 0);
  add_lowered_floor(w, 1.0, 0.0, 1.0);
  w.init();
  w.steps = 250;
  w.place_moving_walls();
  EXPECT_NEAR(w.geometry.walls[0].ay, -0.025, 1e-15);
  EXPECT_NEAR(w.moving.translating[0].y, -0.025, 1e-15);
}
