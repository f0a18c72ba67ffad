// Disc kinds (discs.hpp): discs with the same radius, density and material share one entry of
// constants, any difference makes a new one, and the constants are those of the paper's disc
// (m = rho pi r^2, I = m r^2 / 2) whatever the order of adding.
#include <gtest/gtest.h>

#include <cmath>

#include "discs.hpp"

namespace dem {
namespace {

TEST(DiscKinds, SharedByEqualConstantsOnly) {
  Discs d;
  const double radii[3] = {0.5, 0.4, 0.5 + 1e-15};
  for (int k = 0; k < 3000; ++k) d.add(k, 0, radii[k % 3], k % 2 ? 2.65 : 1.0, k % 5 == 0 ? 1 : 0);
  // 3 radii x 2 densities x 2 materials, all combinations met.
  EXPECT_EQ(d.kinds.size(), 12u);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const int k = static_cast<int>(i);
    const double r = radii[k % 3], rho = k % 2 ? 2.65 : 1.0;
    const double m = rho * M_PI * r * r;
    ASSERT_EQ(d.r(i), r);
    ASSERT_DOUBLE_EQ(d.mass(i), m);
    ASSERT_DOUBLE_EQ(d.inv_mass(i), 1 / m);
    ASSERT_DOUBLE_EQ(d.inv_inertia(i), 1 / (0.5 * m * r * r));
    ASSERT_EQ(d.material(i), k % 5 == 0 ? 1 : 0);
  }
  // Every disc its own radius: one kind each.
  Discs poly;
  for (int k = 0; k < 5000; ++k) poly.add(k, 0, 0.3 + 1e-4 * k, 2.65, 0);
  EXPECT_EQ(poly.kinds.size(), 5000u);
  for (std::size_t i = 0; i < poly.size(); ++i) ASSERT_EQ(poly.r(i), 0.3 + 1e-4 * static_cast<double>(i));
  // The index may be dropped and rebuilt: later discs still find their kinds.
  poly.forget_kind_index();
  poly.add(0, 1, 0.3, 2.65, 0);
  EXPECT_EQ(poly.kinds.size(), 5000u);
  EXPECT_EQ(poly.kind.back(), poly.kind.front());
}

TEST(DiscKinds, HoldGivesOneDiscItsOwnKind) {
  Discs d;
  for (int k = 0; k < 4; ++k) d.add(k, 0, 0.5, 2.65, 0);
  d.hold(2);
  EXPECT_EQ(d.kinds.size(), 2u);
  EXPECT_EQ(d.inv_mass(2), 0.0);
  EXPECT_EQ(d.inv_inertia(2), 0.0);
  EXPECT_EQ(d.r(2), 0.5);
  EXPECT_EQ(d.mass(2), d.mass(1));
  EXPECT_GT(d.inv_mass(1), 0.0);
}

}  // namespace
}  // namespace dem
