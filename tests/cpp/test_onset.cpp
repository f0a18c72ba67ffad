// integrator.scheme = "velocity_verlet_onset" (physics/onset.cpp): second order in a collision.
// References are closed forms: the head-on clamped spring-dashpot (the contact ends where
// k x + c x' = 0; Schwager & Poeschel 2007) and a disc launched along a floor, whose contact
// sticks (a damped tangential oscillator of mass m/3) until the spring meets mu m g, then slides.
// Errors are RMS over start phases of the event within a step; halving dt divides an error of
// order p by 2^p: about 4 for this scheme, about 2 for velocity Verlet.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "helpers.hpp"
#include "io/state.hpp"
#include "scene/scene.hpp"

using namespace dem;
using namespace dem::testing;

namespace {

const double kRho = 2.65, kR = 1.0;
const double kMass = kRho * M_PI * kR * kR;
const double kKn = 9.45e7;  // the paper's K_n (3.64e4 rho g)
const double kZeta = 0.3;
const double kV0 = 50.0;    // cm/s, as compare/verdict/calibration.py's collisions

// The clamped head-on contact, exactly: overlap x(t) = v0/wd e^{-b t} sin(wd t) until the force
// k x + c x' vanishes at t1; then the bodies fly apart at -x'(t1): e = -x'(t1) / v0.
double exact_e(double m_eff) {
  const double w0 = std::sqrt(kKn / m_eff), b = kZeta * w0, wd = w0 * std::sqrt(1 - kZeta * kZeta);
  const double c = 2 * kZeta * std::sqrt(m_eff * kKn);
  auto x = [&](double t) { return kV0 / wd * std::exp(-b * t) * std::sin(wd * t); };
  auto v = [&](double t) { return kV0 * std::exp(-b * t) * (std::cos(wd * t) - b / wd * std::sin(wd * t)); };
  double lo = 0.5 * M_PI / wd, hi = M_PI / wd;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (kKn * x(mid) + c * v(mid) > 0 ? lo : hi) = mid;
  }
  return -v(lo) / kV0;
}

double contact_time(double m_eff) { return M_PI / std::sqrt(kKn / m_eff * (1 - kZeta * kZeta)); }

// Head-on impact at v0 on a wall (or of two discs at +-v0/2), starting `phase` of a step before a
// step edge; the restitution from the velocities once the discs are apart.
double head_on_e(bool wall, Scheme scheme, double dt, double phase) {
  const double m_eff = wall ? kMass : kMass / 2;
  World w = make_world(linear(kKn, kZeta, m_eff), shared_law(), scheme, dt);
  const double gap = kV0 * dt * (3 + phase);
  if (wall) {
    w.geometry.walls.push_back({"wall", "wall", 0, -10, 0, 10, 1});
    w.discs.add(-kR - gap, 0, kR, kRho, 0);
    w.discs.vx[0] = kV0;
  } else {
    w.discs.add(-kR - gap / 2, 0, kR, kRho, 0);
    w.discs.add(kR + gap / 2, 0, kR, kRho, 0);
    w.discs.vx = {kV0 / 2, -kV0 / 2};
  }
  w.init();
  const long steps = static_cast<long>((gap / kV0 + 2.5 * contact_time(m_eff)) / dt);
  for (long s = 0; s < steps; ++s) w.step();
  return (wall ? -w.discs.vx[0] : w.discs.vx[1] - w.discs.vx[0]) / kV0;
}

double rms_error_e(bool wall, Scheme scheme, double dt) {
  const double e_ref = exact_e(wall ? kMass : kMass / 2);
  double sum = 0;
  const int phases = 4;
  for (int k = 0; k < phases; ++k) {
    const double err = head_on_e(wall, scheme, dt, (k + 0.5) / phases) / e_ref - 1;
    sum += err * err;
  }
  return std::sqrt(sum / phases);
}

}  // namespace

// dt = t_c / 100 and t_c / 200: the ratio of the errors is 2^order.
TEST(Onset, HeadOnRestitutionErrorIsSecondOrder) {
  for (bool wall : {true, false}) {
    const double dt = contact_time(wall ? kMass : kMass / 2) / 100;
    const double vv1 = rms_error_e(wall, Scheme::velocity_verlet, dt);
    const double vv2 = rms_error_e(wall, Scheme::velocity_verlet, dt / 2);
    const double on1 = rms_error_e(wall, Scheme::velocity_verlet_onset, dt);
    const double on2 = rms_error_e(wall, Scheme::velocity_verlet_onset, dt / 2);
    std::printf("%s: dt %.3g s: velocity_verlet %.3e -> %.3e (ratio %.2f); onset %.3e -> %.3e (ratio %.2f)\n",
                wall ? "disc-wall" : "disc-disc", dt, vv1, vv2, vv1 / vv2, on1, on2, on1 / on2);
    EXPECT_GT(vv1 / vv2, 1.6) << "velocity Verlet is first order";
    EXPECT_LT(vv1 / vv2, 2.6) << "velocity Verlet is first order";
    EXPECT_GT(on1 / on2, 3.2) << "the onset scheme must be second order";
    EXPECT_LT(on1 / on2, 5.0) << "the onset scheme must be second order";
    EXPECT_LT(on1, vv1 / 5) << "and far more accurate at the same dt";
  }
}

namespace {

// A disc resting on a floor (N = m g) launched at u0 along it, no spin, lever arm r. The contact
// point's slip s obeys (m/3) s'' = -k_s s - eta_s s' while it sticks (1/m_t = 1/m + r^2/I, I =
// m r^2 / 2), from s = 0, s' = u0, until k_s s meets mu N at t_s; then it slides under mu N
// alone (the dashpot off, eq. 13b). The centre's velocity at T > t_s (still sliding):
// u0 - (m_t (u0 - s'(t_s)) + mu N (T - t_s)) / m.
struct Floor {
  double ks = kKn / 4, mu = 0.5, g = 980, zeta_t = 0.3;
  double mt = kMass / 3;
  double eta_s = 2 * zeta_t * std::sqrt(mt * ks);
  double exact_v(double u0, double T) const {
    const double w0 = std::sqrt(ks / mt), b = zeta_t * w0, wd = w0 * std::sqrt(1 - zeta_t * zeta_t);
    auto s = [&](double t) { return u0 / wd * std::exp(-b * t) * std::sin(wd * t); };
    auto sd = [&](double t) { return u0 * std::exp(-b * t) * (std::cos(wd * t) - b / wd * std::sin(wd * t)); };
    const double cap = mu * kMass * g;
    double lo = 0, hi = 0.5 * M_PI / wd;  // k_s s rises from 0 past the cap before its first peak
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (ks * s(mid) < cap ? lo : hi) = mid;
    }
    return u0 - (mt * (u0 - sd(lo)) + cap * (T - lo)) / kMass;
  }
  double simulate(Scheme scheme, double dt, double u0, double T) const {
    PairProps p = linear(kKn, 0.5, kMass, mu, ks, eta_s);
    ContactOptions o = shared_law();
    o.lever_arm = LeverArm::radius;
    World w = make_world(p, o, scheme, dt, -g);
    w.geometry.walls.push_back({"floor", "floor", -10, 0, 10, 0, 1});
    w.discs.add(0, kR - kMass * g / kKn, kR, kRho, 0);  // at rest on the floor: k_n overlap = m g
    w.discs.vx[0] = u0;
    w.init();
    const long steps = std::lround(T / dt);
    for (long k = 0; k < steps; ++k) w.step();
    return w.discs.vx[0];
  }
};

}  // namespace

// The error's phase dependence is strong here (one event, the slip onset, carries the first-order
// term): sixteen launch speeds, and dt against dt / 4, whose error ratio is 4^order.
TEST(Onset, SlipOnsetMatchesTheStickSlipClosedForm) {
  const Floor f;
  const double T = 4e-4;  // s: after the slip starts (about 1e-4 s), before it ends
  auto rms = [&](Scheme scheme, double dt) {
    double sum = 0;
    const int n = 16;
    for (int k = 0; k < n; ++k) {  // each launch speed meets the cap at another phase of a step
      const double u0 = 1.5 + 0.025 * k;
      const double err = (f.simulate(scheme, dt, u0, T) - f.exact_v(u0, T)) / u0;
      sum += err * err;
    }
    return std::sqrt(sum / n);
  };
  const double dt = 8e-6;  // about t_s / 13
  const double vv1 = rms(Scheme::velocity_verlet, dt), vv4 = rms(Scheme::velocity_verlet, dt / 4);
  const double on1 = rms(Scheme::velocity_verlet_onset, dt), on4 = rms(Scheme::velocity_verlet_onset, dt / 4);
  const double p_vv = std::log(vv1 / vv4) / std::log(4.0), p_on = std::log(on1 / on4) / std::log(4.0);
  std::printf("slip onset: velocity_verlet %.3e -> %.3e (order %.2f); onset %.3e -> %.3e (order %.2f)\n", vv1, vv4,
              p_vv, on1, on4, p_on);
  EXPECT_GT(p_vv, 0.7);
  EXPECT_LT(p_vv, 1.3) << "velocity Verlet is first order";
  EXPECT_GT(p_on, 1.6) << "the slip onset must be second order";
  EXPECT_LT(p_on, 2.4);
  EXPECT_LT(on1, vv1 / 5);
}

namespace {

SceneSpec silo_10k(int threads) {
  SceneOverrides ov;
  ov.scheme = "velocity_verlet_onset";
  ov.dt = 2e-5;
  ov.force_dt = true;
  ov.sets = {"contact.normal_spring=overlap", "contact.no_tension=total", "contact.friction_cap=total",
             "contact.lever_arm=contact_point"};  // the shared law
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov);
  spec.threads = threads;
  return spec;
}

}  // namespace

// The 10k-disc lattice silo as its first contacts form: 1 and 2 threads, the same bits.
TEST(Onset, SameBitsAnyThreadCount) {
  std::uint64_t hash[2];
  for (int threads : {1, 2}) {
    World w;
    build_world(silo_10k(threads), w);
    if (threads == 2) {
      ASSERT_EQ(w.threads_for(static_cast<int>(w.discs.size())), 2) << "the test needs 2 threads";
    }
    for (int s = 0; s < 300; ++s) w.step();
    long touching = 0;
    for (const PairContact& p : w.neighbors.pairs) touching += p.en != 0;
    EXPECT_GT(touching, 100) << "contacts must form (onsets inside steps)";
    hash[threads - 1] = state_hash(w.discs);
  }
  EXPECT_EQ(hash[0], hash[1]);
}

// A run split through a saved state equals the run in one piece: the scheme keeps no state of
// its own between steps (v(t) and the missed impulses live inside a step).
TEST(Onset, ResumeThroughSavedStateIsBitIdentical) {
  const SceneSpec spec = silo_10k(2);
  World b, c;
  build_world(spec, b);
  build_world(spec, c);
  const long steps = 400, split = 157;
  for (long s = 0; s < steps; ++s) b.step();
  for (long s = 0; s < split; ++s) c.step();
  const std::string path = ::testing::TempDir() + "/onset_split.state";
  save_state(c, path);
  World d;
  build_world(spec, d);
  load_state(d, path);
  std::remove(path.c_str());
  for (long s = split; s < steps; ++s) d.step();
  ASSERT_EQ(b.discs.size(), d.discs.size());
  EXPECT_EQ(state_hash(b.discs), state_hash(d.discs));
}

TEST(Onset, RefusesTheIncrementalSpring) {
  World w = make_world(linear(kKn, kZeta, kMass), ContactOptions{}, Scheme::velocity_verlet_onset, 1e-6);
  w.discs.add(0, 0, kR, kRho, 0);
  EXPECT_THROW(w.init(), std::invalid_argument);
}
