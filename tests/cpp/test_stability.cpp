// Time-step bounds from the scheme's own step matrix against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "stability.hpp"

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
