// The integration loop (World::move_block: kick, drift and the skin/2 test) runs several
// discs a vector, two (SSE2), four (AVX2) or eight (AVX-512; World::vector_width, the widest the
// processor has, unless a world is set narrower): each disc must still get
// exactly eqs. (17)-(19) as written, whatever its place in a vector (the loop's remainder
// included), with one kind of disc or several; the skin/2 test must catch a single far disc
// anywhere; and every vector width must give the bits of two over whole runs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "helpers.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

// n discs in a loose row (no contacts), random velocities, forces and eq. 19 increments; two
// radii when several_kinds.
World row_world(Scheme scheme, int n, bool several_kinds, bool angle, unsigned seed, int width) {
  PairProps p = testing::linear(9.45e7, 0.3, 4.16, 0.577, 2.36e7, 2.0e4);
  World w = testing::make_world(p, ContactOptions{}, scheme, 1e-4, -980.0);
  w.set_vector_width(width);
  w.rotation_angle = angle;
  for (int i = 0; i < n; ++i) w.discs.add(3.0 * i, 0.0, several_kinds && i % 3 == 1 ? 0.7 : 1.0, 2.65, 0);
  w.prepare();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Discs& d = w.discs;
  for (int i = 0; i < n; ++i) {
    d.vx[i] = 5 * u(rng); d.vy[i] = 5 * u(rng); d.omega[i] = 5 * u(rng);
    d.fx[i] = 1e4 * u(rng); d.fy[i] = 1e4 * u(rng); d.torque[i] = 1e4 * u(rng);
    if (!d.dux.empty()) { d.dux[i] = 1e-4 * u(rng); d.duy[i] = 1e-4 * u(rng); d.dphi[i] = 1e-4 * u(rng); }
    if (!d.phi.empty()) d.phi[i] = u(rng);
  }
  return w;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// Eq. (17) and the drift of (18) or (19), disc by disc, as the paper writes them.
TEST(IntegrationKernels, EveryDiscGetsTheSchemeAsWritten) {
  for (int width : {2, 4, 8}) {
    if (width > World::cpu_vector_width()) continue;
    for (Scheme scheme : {Scheme::paper_eq18, Scheme::paper_eq19})
      for (bool kinds : {false, true})
        for (bool angle : {false, true})
          for (int n : {1, 3, 4, 5, 8, 9, 37}) {  // remainders of two, four and eight discs a vector
            World w = row_world(scheme, n, kinds, angle, 17u + static_cast<unsigned>(n), width);
            const Discs before = w.discs;
            const double h = 0.7e-4, dt = w.dt;
            if (scheme == Scheme::paper_eq19) w.kick_drift_eq19(h);
            else w.kick_drift_eq18(h);
            const Discs& d = w.discs;
            for (int i = 0; i < n; ++i) {
              const Discs& b = before;
              const double v = b.vx[i] + b.fx[i] * b.inv_mass(i) * h;  // (17)
              const double vy = b.vy[i] + b.fy[i] * b.inv_mass(i) * h;
              const double o = b.omega[i] + b.torque[i] * b.inv_inertia(i) * h;
              double a = v * dt, c = vy * dt, e = o * dt;  // (18)
              if (scheme == Scheme::paper_eq19) {           // (19)
                a = 0.5 * (b.dux[i] + v * dt);
                c = 0.5 * (b.duy[i] + vy * dt);
                e = 0.5 * (b.dphi[i] + o * dt);
                EXPECT_EQ(d.dux[i], a); EXPECT_EQ(d.duy[i], c); EXPECT_EQ(d.dphi[i], e);
              }
              EXPECT_EQ(d.vx[i], v); EXPECT_EQ(d.vy[i], vy); EXPECT_EQ(d.omega[i], o);
              EXPECT_EQ(d.x[i], b.x[i] + a); EXPECT_EQ(d.y[i], b.y[i] + c);
              if (angle) {
                EXPECT_EQ(d.phi[i], b.phi[i] + e);
              }
              if (::testing::Test::HasFailure()) {
                FAIL() << "disc " << i << " of " << n << ", " << width << " doubles a vector" << (kinds ? ", two kinds" : "")
                       << (angle ? ", angle kept" : "");
              }
            }
          }
  }
}

// One disc past skin/2 from its list position, at any place (vector lanes and the remainder):
// the drift reports it; the same disc just short of the limit: not reported.
TEST(IntegrationKernels, OneFarDiscAnywhereIsCaught) {
  for (int width : {2, 4, 8}) {
    if (width > World::cpu_vector_width()) continue;
    const int n = 23;
    for (int far_one = 0; far_one < n; ++far_one)
      for (bool past : {false, true}) {
        World w = row_world(Scheme::paper_eq18, n, false, false, 5, width);
        Discs& d = w.discs;
        std::fill(d.vx.begin(), d.vx.end(), 0.0); std::fill(d.vy.begin(), d.vy.end(), 0.0);
        std::fill(d.fx.begin(), d.fx.end(), 0.0); std::fill(d.fy.begin(), d.fy.end(), 0.0);
        const double lim = std::sqrt(w.neighbors.moved_far_limit2());
        // With no force, eq. 18 moves the disc by exactly v dt.
        d.vx[far_one] = (past ? 1.001 : 0.999) * lim / w.dt;
        EXPECT_EQ(w.kick_drift_eq18(0.0), past) << "disc " << far_one << ", " << width << " doubles a vector";
      }
  }
}

// Whole runs of a dense packing under gravity, every scheme, one kind or two, 1 and 2 threads:
// four and eight discs a vector give the bits of two.
TEST(IntegrationKernels, WideAndNarrowGiveTheSameBitsOverARun) {
  if (World::cpu_vector_width() < 4) GTEST_SKIP() << "this processor has no AVX2: only the SSE2 loops run";
  for (Scheme scheme : testing::kSchemes)
    for (bool kinds : {false, true})
      for (int threads : {1, 2}) {
        std::vector<Discs> out;
        std::vector<long> rebuilds;
        for (int width : {2, 4, 8}) {
          if (width > World::cpu_vector_width()) continue;
          PairProps p = testing::linear(9.45e7, 0.3, 4.16, 0.577, 2.36e7, 2.0e4);
          World w = testing::make_world(p, ContactOptions{}, scheme, 5e-5, -980.0);
          w.set_vector_width(width);
          w.threads = threads;
          std::mt19937 rng(3);
          std::uniform_real_distribution<double> jitter(-0.02, 0.02);
          for (int r = 0; r < 70; ++r)
            for (int c = 0; c < 70; ++c)
              w.discs.add(2.0 * c + (r % 2) + jitter(rng), 1.8 * r + jitter(rng), kinds && (r + c) % 4 == 0 ? 0.9 : 1.0,
                          2.65, 0);
          w.rotation_angle = kinds;
          w.init();
          for (int s = 0; s < 300; ++s) w.step();
          out.push_back(w.discs);
          rebuilds.push_back(w.neighbors.rebuilds);
        }
        for (std::size_t k = 1; k < out.size(); ++k) {  // out[0]: two a vector
          const Discs &a = out[0], &b = out[k];
          EXPECT_TRUE(same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.vx, b.vx) && same_bits(a.vy, b.vy) &&
                      same_bits(a.omega, b.omega) && same_bits(a.dux, b.dux) && same_bits(a.phi, b.phi))
              << to_string(scheme) << (kinds ? ", two kinds" : "") << ", " << threads << " threads, "
              << (k == 1 ? 4 : 8) << " a vector";
          EXPECT_EQ(rebuilds[0], rebuilds[k]);
        }
        EXPECT_GT(rebuilds[0], 1) << "the run rebuilt its lists";
      }
}

}  // namespace
}  // namespace dem
