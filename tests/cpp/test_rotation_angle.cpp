// The rotation angle phi (the last line of eqs. 18 and 19, World::rotation_angle): an output the
// law never reads. Asked for, each step adds the rotation increment the law used (eqs. 18, 19)
// and a free disc turns by omega dt a step, for each scheme; not asked for, no array is kept, and the motion is the same bit for bit.
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

using testing::kSchemes;
using testing::linear;
using testing::make_world;

// Two discs in a sliding, spinning collision (friction turns them), then flying apart spinning.
World collision(Scheme scheme, bool angle) {
  const PairProps p = linear(1e7, 0.3, 0.5 * 2.65 * M_PI, 0.5, 2.5e6, 1e3);
  World w = make_world(p, {}, scheme, 2e-5);
  w.discs.add(0, 0, 1, 2.65, 0);
  w.discs.add(1.999, 0.6, 1, 2.65, 0);
  w.discs.vx[0] = 50;
  w.discs.omega[1] = 30;
  w.rotation_angle = angle;
  w.init();
  return w;
}

TEST(RotationAngle, AddsEachStepsIncrementWhenAskedNoArrayOtherwise) {
  for (Scheme scheme : kSchemes) {
    World with = collision(scheme, true), without = collision(scheme, false);
    ASSERT_EQ(with.discs.phi.size(), 2u);
    EXPECT_TRUE(without.discs.phi.empty()) << "no angle array unless asked";
    for (int s = 0; s < 3000; ++s) {
      const double phi0[2] = {with.discs.phi[0], with.discs.phi[1]};
      with.step();
      without.step();
      ASSERT_EQ(with.discs.x[1], without.discs.x[1]) << "the angle changes nothing else";
      ASSERT_EQ(with.discs.omega[0], without.discs.omega[0]);
      // The step's angle increment is the one the law used: eq. 19 stores it (dphi), eq. 18's
      // is omega dt with the omega after the kick. (Verlet's uses the half-kick omega, which its
      // closing kick overwrites: checked by the free spin below.)
      for (int i = 0; i < 2; ++i) {
        const double turned = with.discs.phi[i] - phi0[i];
        if (scheme == Scheme::paper_eq19) {
          ASSERT_NEAR(turned, with.discs.dphi[i], 1e-15 + 1e-12 * std::abs(turned));
        }
        if (scheme == Scheme::paper_eq18) {
          ASSERT_NEAR(turned, with.discs.omega[i] * with.dt, 1e-15 + 1e-12 * std::abs(turned));
        }
      }
    }
    for (int i = 0; i < 2; ++i) EXPECT_GT(std::abs(with.discs.phi[i]), 1e-3) << "disc " << i << " turned";
    // After the collision the discs spin freely: the angle grows by omega dt a step.
    const double phi_before = with.discs.phi[1], omega = with.discs.omega[1];
    for (int s = 0; s < 100; ++s) with.step();
    EXPECT_NEAR(with.discs.phi[1] - phi_before, 100 * omega * with.dt, 1e-9 * std::abs(100 * omega * with.dt));
  }
}

}  // namespace
}  // namespace dem
