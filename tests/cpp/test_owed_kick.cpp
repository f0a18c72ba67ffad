// Velocity Verlet's closing half kick owed to the next step's first sweep
// (World::defer_closing_kick): the same bits as the kick in its own sweep, at one thread and two;
// v(t) read through velocity_now while it is owed; readers of v(t) refused until it is paid; and
// never owed where the step cannot defer it.
#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/world.hpp"
#include "janssen_bin.hpp"
#include "scene/scene.hpp"

using namespace dem;

namespace {

// The Janssen bin (velocity Verlet, 4500 discs of several radii) under 100 g: its loose start
// packs into contact within a few hundred steps.
SceneSpec janssen(int threads) {
  SceneSpec spec = dem::testing::janssen_bin(threads);
  spec.gx *= 100;
  spec.gy *= 100;
  return spec;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The state a step leaves: positions, velocities, resultants.
void expect_same_state(const Discs& a, const Discs& b) {
  EXPECT_TRUE(same_bits(a.x, b.x));
  EXPECT_TRUE(same_bits(a.y, b.y));
  EXPECT_TRUE(same_bits(a.vx, b.vx));
  EXPECT_TRUE(same_bits(a.vy, b.vy));
  EXPECT_TRUE(same_bits(a.omega, b.omega));
  EXPECT_TRUE(same_bits(a.fx, b.fx));
  EXPECT_TRUE(same_bits(a.fy, b.fy));
  EXPECT_TRUE(same_bits(a.torque, b.torque));
}

}  // namespace

// 600 steps with the kick owed (paid once in the middle, as a run pays it on its check steps)
// against 600 with the kick in its own sweep: every array the same bits after each pay, and
// velocity_now gives the kicked velocities while the kick is owed.
TEST(OwedKick, SameBitsAsTheKickInItsOwnSweep) {
  for (int threads : {1, 2}) {
    World a, b;
    build_world(janssen(threads), a);
    build_world(janssen(threads), b);
    ASSERT_EQ(a.scheme, Scheme::velocity_verlet);
    b.defer_closing_kick = true;
    long touching = 0;
    for (int s = 1; s <= 600; ++s) {
      a.step();
      b.step();
      ASSERT_TRUE(b.kick_owed());
      if (s % 150 == 0) {
        for (std::size_t i = 0; i < b.discs.size(); ++i) {
          double vx, vy;
          b.velocity_now(i, vx, vy);
          ASSERT_TRUE(same_bits(vx, a.discs.vx[i]) && same_bits(vy, a.discs.vy[i]))
              << "disc " << i << " step " << s << ", " << threads << " thread(s)";
        }
      }
      if (s == 300) {
        b.pay_kick();
        EXPECT_FALSE(b.kick_owed());
        expect_same_state(a.discs, b.discs);
      }
    }
    b.pay_kick();
    expect_same_state(a.discs, b.discs);
    for (const PairContact& c : a.neighbors.pairs) touching += c.en != 0;
    EXPECT_GT(touching, 200) << "the bin should be in contact: contact forces then differ disc by disc";
  }
}

// While the kick is owed, the world's readers of v(t) (the energy, the finite check, a state's
// writer through require_velocities) refuse with a logic error; after pay_kick they give v(t)'s.
TEST(OwedKick, ReadersOfVelocitiesRefusedWhileOwed) {
  World a, b;
  build_world(janssen(1), a);
  build_world(janssen(1), b);
  b.defer_closing_kick = true;
  for (int s = 0; s < 30; ++s) {
    a.step();
    b.step();
  }
  EXPECT_THROW(b.kinetic_energy(), std::logic_error);
  EXPECT_THROW(b.all_finite(), std::logic_error);
  EXPECT_THROW(b.require_velocities("test"), std::logic_error);
  b.pay_kick();
  EXPECT_TRUE(same_bits(b.kinetic_energy(), a.kinetic_energy()));
  EXPECT_TRUE(b.all_finite());
}

// The paper's schemes move after their forces (nothing to defer), and a velocity Verlet world
// with moving walls kicks its plates with its discs: neither owes the kick.
TEST(OwedKick, NeverOwedWhereTheStepCannotDeferIt) {
  World w;
  SceneSpec spec = janssen(1);
  spec.scheme = Scheme::paper_eq19;
  spec.force_dt = true;
  build_world(spec, w);
  w.defer_closing_kick = true;
  w.step();
  EXPECT_FALSE(w.kick_owed());
  World v;
  build_world(janssen(1), v);
  v.defer_closing_kick = false;
  v.step();
  EXPECT_FALSE(v.kick_owed());
}
