// The kernel list (physics/kernels.hpp): the kernels compiled are exactly the rows it declares
// (each law with each feature set, then the moves, in its order, each once), row_of finds each,
// and a world runs the row of its law and of what it uses: a feature it does not use (shear,
// dashpots, bonds, moving walls) is absent from its kernel.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "helpers.hpp"
#include "physics/contact_law.hpp"
#include "physics/kernels.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

PairProps full_props() { return testing::linear(9.45e7, 0.3, 4.16, 0.577, 2.36e7, 2.0e4); }

// Two touching discs on a floor.
World two_discs(const PairProps& p, ContactOptions opt = {}) {
  World w = testing::make_world(p, opt, Scheme::paper_eq19, 1e-4, -980.0);
  w.geometry.walls.push_back({"floor", "bottom", -10, 0, 10, 0, 1});
  w.discs.add(0, 1, 1, 2.65, 0);
  w.discs.add(1.99, 1, 1, 2.65, 0);
  return w;
}

bool has(const std::string& name, const std::string& word) {
  return (" " + name + " ").find(" " + word + " ") != std::string::npos;
}

TEST(Kernels, TheCompiledListIsTheDeclaredOne) {
  const std::vector<std::string> names = World::kernel_names();
  ASSERT_EQ(names.size(), kKernelCount + kMoveCount);
  EXPECT_EQ(kKernelCount, kLawCount * kFeatureCount);
  for (std::size_t k = 0; k < kKernelCount; ++k) EXPECT_EQ(names[k], kernel_name(kernel_key(k))) << k;
  for (std::size_t m = 0; m < kMoveCount; ++m) EXPECT_EQ(names[kKernelCount + m], kernel_name(kMoves[m])) << m;
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size()) << "a row compiled twice";
  for (std::size_t k = 0; k < kKernelCount; ++k) EXPECT_EQ(row_of(kKernels, kernel_key(k)), k);
  for (std::size_t m = 0; m < kMoveCount; ++m) EXPECT_EQ(row_of(kMoves, kMoves[m]), m);
  std::printf("%zu force rows (%zu laws x %zu feature sets), %zu move rows:\n", kKernelCount, kLawCount, kFeatureCount,
              kMoveCount);
  for (const std::string& n : names) std::printf("  %s\n", n.c_str());
}

TEST(Kernels, EveryLawAndArmSelectsItsRow) {
  for (const Law& law : kLaws)
    for (LeverArm arm : {LeverArm::radius, LeverArm::contact_point}) {
      World w = two_discs(full_props(), {law.normal_spring, law.no_tension, law.friction_cap, arm});
      w.init();
      EXPECT_EQ(w.kernel_name(), kernel_name({law, {arm, true, true, false, false}}));
    }
}

// Under the overlap spring no touching contact (overlap >= 0) has e_n < 0: the no-tension rule on
// the overlap gives the elastic rule's bits, and such a scene runs the elastic rule's row.
TEST(Kernels, TheOverlapRuleOfTheOverlapSpringIsTheElasticRow) {
  const PairProps p = full_props();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  for (int k = 0; k < 20000; ++k) {
    const double overlap = k % 10 == 0 ? 0.0 : std::abs(u(rng)) * 0.05, du_n = u(rng) * 0.01, du_s = u(rng) * 0.01;
    const double en0 = u(rng) * 1e6, es0 = u(rng) * 1e6;
    double ea = en0, sa = es0, fna, fsa, eb = en0, sb = es0, fnb, fsb;
    contact_law<NormalSpring::overlap, NoTension::overlap, FrictionCap::total>(p, overlap, du_n, du_s, 1e4, ea, sa, fna, fsa);
    contact_law<NormalSpring::overlap, NoTension::elastic, FrictionCap::total>(p, overlap, du_n, du_s, 1e4, eb, sb, fnb, fsb);
    ASSERT_TRUE(same(ea, eb) && same(sa, sb) && same(fna, fnb) && same(fsa, fsb)) << k;
    ea = eb = en0; sa = sb = es0;
    contact_law<NormalSpring::overlap, NoTension::overlap, FrictionCap::elastic>(p, overlap, du_n, du_s, 1e4, ea, sa, fna, fsa);
    contact_law<NormalSpring::overlap, NoTension::elastic, FrictionCap::elastic>(p, overlap, du_n, du_s, 1e4, eb, sb, fnb, fsb);
    ASSERT_TRUE(same(ea, eb) && same(sa, sb) && same(fna, fnb) && same(fsa, fsb)) << k;
  }
  for (FrictionCap cap : {FrictionCap::elastic, FrictionCap::total}) {
    World a = two_discs(p, {NormalSpring::overlap, NoTension::overlap, cap, LeverArm::radius});
    a.init();
    EXPECT_EQ(a.kernel_name(), kernel_name({{NormalSpring::overlap, NoTension::elastic, cap}, {LeverArm::radius, true, true, false, false}}));
  }
}

// velocity_verlet_onset's pass is its row's: the overlap spring's rows have it, the others not.
TEST(Kernels, TheOnsetSchemeRunsItsRow) {
  ContactOptions o;
  o.normal_spring = NormalSpring::overlap;
  World w = two_discs(full_props(), o);
  w.scheme = Scheme::velocity_verlet_onset;
  w.init();
  for (int s = 0; s < 10; ++s) w.step();
  EXPECT_TRUE(w.all_finite());
  World v = two_discs(full_props());
  v.scheme = Scheme::velocity_verlet_onset;
  EXPECT_THROW(v.init(), std::invalid_argument);  // the incremental spring: no onset row
}

TEST(Kernels, AnUnusedFeatureIsNotInTheKernel) {
  {  // the paper's law with shear and dashpots, fixed walls, no clusters
    World w = two_discs(full_props());
    w.init();
    EXPECT_TRUE(has(w.kernel_name(), "shear") && has(w.kernel_name(), "dashpots")) << w.kernel_name();
    EXPECT_FALSE(has(w.kernel_name(), "bonds")) << w.kernel_name();
    EXPECT_FALSE(has(w.kernel_name(), "moving_walls")) << w.kernel_name();
  }
  {  // no shear spring or dashpot: no shear, and the radius arm whatever the option (no arm is read)
    PairProps p = full_props();
    p.ks = p.eta_s = 0;
    ContactOptions o;
    o.lever_arm = LeverArm::contact_point;
    World w = two_discs(p, o);
    w.init();
    EXPECT_FALSE(has(w.kernel_name(), "shear")) << w.kernel_name();
    EXPECT_TRUE(has(w.kernel_name(), "radius")) << w.kernel_name();
    EXPECT_FALSE(w.kernel_shear);
  }
  {  // no dashpots
    PairProps p = full_props();
    p.eta_n = p.eta_s = 0;
    World w = two_discs(p);
    w.init();
    EXPECT_FALSE(has(w.kernel_name(), "dashpots")) << w.kernel_name();
    EXPECT_FALSE(w.kernel_dashpots);
  }
  {  // a bond: the bond stage is in; removing a bonded disc takes it out again
    World w = two_discs(full_props());
    Bond b;
    b.i = 0;
    b.j = 1;
    b.ai = b.aj = 1;
    b.rest = 1.99;
    w.bonds.push_back(b);
    w.init();
    EXPECT_TRUE(has(w.kernel_name(), "bonds")) << w.kernel_name();
    RemovedDiscs gone;
    gone.sorted = {1};
    w.remove_discs(gone);
    EXPECT_FALSE(has(w.kernel_name(), "bonds")) << w.kernel_name();
  }
  {  // a rotating wall
    World w = two_discs(full_props());
    RotatingWall r;
    r.wall = 0;
    r.ax0 = -10; r.bx0 = 10;
    r.reach = 10;
    r.omega = 0.1;
    w.moving.rotating.push_back(r);
    w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
    w.init();
    EXPECT_TRUE(has(w.kernel_name(), "moving_walls")) << w.kernel_name();
  }
}

TEST(Kernels, VectorWidthIsAWorldsOwn) {
  World w = two_discs(full_props());
  EXPECT_EQ(w.vector_width_used(), World::vector_width);
  w.set_vector_width(2);
  EXPECT_EQ(w.vector_width_used(), 2);
  EXPECT_THROW(w.set_vector_width(3), std::invalid_argument);
  if (World::vector_width < 8) {
    EXPECT_THROW(w.set_vector_width(8), std::invalid_argument);
  }
}

}  // namespace
}  // namespace dem
