// A disc on a wall: sliding decelerates at mu_w g and ends rolling at v/v0 = 2/3
// (angular momentum about the contact point: m v0 r = m v r + I v / r, I = m r^2 / 2).
#include <gtest/gtest.h>

#include <cmath>

#include "helpers.hpp"

using namespace dem;
using namespace dem::testing;

namespace {
const double kRho = 2.65, kR = 1.0, kG = 980.0, kMu = 0.176;
const double kMass = kRho * M_PI * kR * kR;

// The paper's wall constants (Table 2) on a disc resting on a floor y = 0, settled first.
World resting_disc(Scheme scheme, double dt) {
  PairProps p;
  const double rg = kRho * kG;
  p.kn = 7.28e4 * rg;
  p.ks = 1.82e4 * rg;
  p.eta_n = 30.6 * rg;
  p.eta_s = 15.3 * rg;
  p.mu = kMu;
  World w = make_world(p, ContactOptions{}, scheme, dt, -kG, &p);
  w.geometry.walls.push_back({"floor", "bottom", -1000, 0, 1000, 0, 1});
  w.discs.add(0, kR - kMass * kG / p.kn, kR, kRho, 0);  // at its static overlap
  w.init();
  for (int s = 0; s < 4000; ++s) w.step();  // settle
  return w;
}
// The settled disc launched sliding at v0 without spin (increment set for eq. 19).
World launched(Scheme scheme, double v0) {
  World w = resting_disc(scheme, 5e-5);
  w.discs.vx[0] = v0;
  if (scheme == Scheme::paper_eq19) w.discs.dux[0] = v0 * w.dt;  // the others read v dt
  return w;
}
}  // namespace

TEST(Friction, SlidingDiscDeceleratesAtMuG) {
  for (Scheme scheme : kSchemes) {
    const double v0 = 50.0;
    World w = launched(scheme, v0);
    // Sliding lasts v0 / (3 mu g) = 0.097 s; measure between 0.02 and 0.07 s.
    for (int s = 0; s < 400; ++s) w.step();
    const double t1 = w.time, v1 = w.discs.vx[0];
    for (int s = 0; s < 1000; ++s) w.step();
    const double a = (w.discs.vx[0] - v1) / (w.time - t1);
    EXPECT_NEAR(a, -kMu * kG, 0.005 * kMu * kG) << to_string(scheme);
    // Spin-up at the same time: alpha = mu m g r / I = 2 mu g / r.
  }
}

TEST(Friction, LaunchedSlidingDiscEndsRollingAtTwoThirds) {
  for (Scheme scheme : kSchemes) {
    const double v0 = 50.0;
    World w = launched(scheme, v0);
    for (int s = 0; s < 8000; ++s) w.step();  // 0.4 s, four times the sliding time
    EXPECT_NEAR(w.discs.vx[0] / v0, 2.0 / 3.0, 2e-3) << to_string(scheme);
    EXPECT_NEAR(-w.discs.omega[0] * kR / w.discs.vx[0], 1.0, 2e-3) << to_string(scheme) << ": not rolling";
  }
}
