// The lists patched for a few far discs instead of rebuilt (Neighbors::patch): every pair and
// every disc-wall pair that touches is listed after any sequence of patches and builds, and a run
// with patches gives the bits of the run that rebuilds, at one thread and two.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "physics/geometry.hpp"
#include "physics/neighbors.hpp"
#include "physics/world.hpp"
#include "scene/scene.hpp"

using namespace dem;

namespace {

bool listed(const std::vector<PairContact>& pairs, int i, int j) {
  return std::any_of(pairs.begin(), pairs.end(), [&](const PairContact& c) { return c.i == i && c.j == j; });
}

bool listed_wall(const std::vector<WallContact>& walls, int i, int k) {
  return std::any_of(walls.begin(), walls.end(), [&](const WallContact& c) { return c.i == i && c.k == k; });
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// The paper's silo (350 discs) with velocity Verlet: its lattice settles, and once the gate
// opens a few discs at a time go far (those flowing out through the slit).
SceneSpec silo() {
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/discharge_17_18.toml");
  spec.scheme = Scheme::velocity_verlet;
  spec.dt = 5e-5;
  return spec;
}

}  // namespace

// 120 discs of radius 1 on a jittered lattice (spacing 2.45: neighbours just beyond the reach
// 2 + skin 0.4, unlisted) over a floor wall; 600 times one to three discs move by 0.25 (past
// skin/2: far at once) in a random direction, toward new partners or away. After each move the
// lists are patched or rebuilt as a step does (World::rebuild_lists) when some disc is more than
// skin/2 from its reference, and then every pair closer than r_i + r_j and every disc closer to
// the floor than r must be listed (checked against all pairs).
TEST(ListPatch, EveryTouchingPairStaysListed) {
  Discs d;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 120; ++k) d.add((k % 12) * 2.45 + 0.02 * u(rng), (k / 12) * 2.45 + 0.02 * u(rng), 1.0, 1.0, 0);
  Geometry g;
  Wall floor;
  floor.ax = -5; floor.ay = -1.3; floor.bx = 35; floor.by = -1.3;
  g.walls.push_back(floor);
  Neighbors nb;
  nb.skin = 0.4;
  nb.rebuild(d, g);
  long missed = 0;
  std::uniform_int_distribution<int> pick(0, 119), how_many(1, 3);
  for (int move = 0; move < 600; ++move) {
    for (int m = how_many(rng); m > 0; --m) {
      const int i = pick(rng);
      const double a = 3.14159265358979 * u(rng);
      d.x[i] += 0.25 * std::cos(a);
      d.y[i] += 0.25 * std::sin(a);
    }
    bool far = false;
    for (std::size_t i = 0; i < d.size(); ++i) {
      const double dx = (d.x[i] - nb.origin_x()) - nb.reference_x()[i], dy = (d.y[i] - nb.origin_y()) - nb.reference_y()[i];
      far |= dx * dx + dy * dy > nb.moved_far_limit2();
    }
    if (far && !nb.patch(d, g)) nb.rebuild(d, g);
    for (int i = 0; i < static_cast<int>(d.size()); ++i) {
      for (int j = i + 1; j < static_cast<int>(d.size()); ++j) {
        const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
        if (dx * dx + dy * dy < 4.0 && !listed(nb.pairs, i, j)) ++missed;
      }
      if (obstacle_distance(g, 0, d.x[i], d.y[i]) < 1.0 && !listed_wall(nb.walls, i, 0)) ++missed;
    }
  }
  EXPECT_EQ(missed, 0) << "touching pairs (or disc-floor pairs) missing from the lists";
  EXPECT_GT(nb.patches, 20) << "the test should patch often";
  EXPECT_GT(nb.rebuilds, 20) << "the test should rebuild often (far discs with new partners)";
}

// A far disc with a partner the lists lack, a disc or a wall: the patch refuses and changes nothing.
TEST(ListPatch, RefusedWhenAFarDiscHasAnUnlistedPartner) {
  Discs d;
  d.add(0.0, 0.0, 1.0, 1.0, 0);
  d.add(2.8, 0.0, 1.0, 1.0, 0);  // 2.8 apart: beyond 2 + skin 0.4, unlisted
  d.add(20.0, 0.0, 1.0, 1.0, 0);
  d.add(30.0, 0.0, 1.0, 1.0, 0);  // the extent (a patch keeps far discs within the build's)
  Geometry g;
  Wall side;  // 2.6 from disc 2: beyond 1 + skin, unlisted
  side.ax = 22.6; side.ay = -10; side.bx = 22.6; side.by = 10;
  g.walls.push_back(side);
  Neighbors nb;
  nb.skin = 0.4;
  nb.rebuild(d, g);
  ASSERT_TRUE(nb.pairs.empty());
  ASSERT_TRUE(nb.walls.empty());
  d.x[2] = 21.4;  // 1.2 from the wall: within 1 + skin, and far
  EXPECT_FALSE(nb.patch(d, g));
  d.x[2] = 20.0;
  const float x0 = nb.reference_x()[0];
  d.x[0] = 0.6;  // now 2.2 from disc 1: within 2 + skin, and far (0.6 > skin/2)
  EXPECT_FALSE(nb.patch(d, g));
  EXPECT_EQ(nb.reference_x()[0], x0);
  d.x[0] = -0.6;  // away from disc 1: nothing new within reach
  EXPECT_TRUE(nb.patch(d, g));
  EXPECT_EQ(nb.patches, 1);
}

// 2000 steps of the silo's fill and 2000 of its discharge with patches and with every far disc rebuilding the lists: the
// same positions, velocities and resultants to the bit. (Threads do not enter: a patch is
// serial and decided by positions, which every thread count gives alike.)
TEST(ListPatch, SameBitsAsRebuilding) {
  World a, b;
  build_world(silo(), a);
  build_world(silo(), b);
  a.neighbors.patch_most = 0;
  for (int s = 0; s < 4000; ++s) {
    if (s == 2000) {  // settled: the gate opens, discs flow out through the slit
      ASSERT_TRUE(a.deactivate_wall("gate"));
      ASSERT_TRUE(b.deactivate_wall("gate"));
    }
    a.step();
    b.step();
  }
  EXPECT_TRUE(same_bits(a.discs.x, b.discs.x));
  EXPECT_TRUE(same_bits(a.discs.y, b.discs.y));
  EXPECT_TRUE(same_bits(a.discs.vx, b.discs.vx));
  EXPECT_TRUE(same_bits(a.discs.omega, b.discs.omega));
  EXPECT_TRUE(same_bits(a.discs.fx, b.discs.fx));
  EXPECT_TRUE(same_bits(a.discs.torque, b.discs.torque));
  EXPECT_EQ(a.neighbors.patches, 0);
  EXPECT_GT(b.neighbors.patches, 10);
  EXPECT_LT(b.neighbors.rebuilds, a.neighbors.rebuilds);
}
