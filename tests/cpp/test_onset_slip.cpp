// velocity_verlet_onset's slip correction between two discs under friction_cap = "total" (the
// shared law, overlap/total/total): the cap at a step's start is mu |f_n| of the last step's end,
// kept per pair (World::onset_normals). The reference is this file's own integration of the
// continuous law: RK4 with the events located (the touch, the slip onset where the spring meets
// mu |f_n| and the shear dashpot switches off), not a value from the engine.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "helpers.hpp"
#include "io/state.hpp"
#include "scene/scene.hpp"

using namespace dem;
using namespace dem::testing;

namespace {

const double kRho = 2.65, kR = 1.0;
const double kMass = kRho * M_PI * kR * kR;
const double kInertia = kMass * kR * kR / 2;
const double kKn = 9.45e7, kZeta = 0.3;
const double kVn = 50.0, kVt = 100.0;  // cm/s: closing speed and tangential speed at the touch
const double kMu = 0.2;                // low: the contact sticks for about t_c / 8, then slides to the end

PairProps oblique_props() {
  const double ks = kKn / 4;
  PairProps p = linear(kKn, kZeta, kMass / 2, kMu, ks, 0.0);
  p.eta_s = p.eta_n * std::sqrt(ks / kKn);  // eq. (25)
  return p;
}

double contact_time() { return M_PI / std::sqrt(kKn / (kMass / 2) * (1 - kZeta * kZeta)); }

// The continuous law for two discs from the touch: state x0 y0 u0 v0 w0 x1 y1 u1 v1 w1 e_s.
// Disc 0 meets disc 1 with the normal +x and the tangent +y at t = 0 (as in the engine, i = 0,
// j = 1: n from 0 to 1, t = (-n_y, n_x), the slip (v_0 - v_1) . t + a_0 w_0 + a_1 w_1 with the
// lever arms a = r - overlap / 2). Sticking: f_s = e_s + eta_s slip, e_s' = k_s slip; sliding:
// f_s = mu |f_n| sign(e_s) (eq. 13); f_n = max(k_n overlap + eta_n overlap', 0).
using State = std::array<double, 11>;

struct Reference {
  PairProps p = oblique_props();
  bool restuck = false;  // the contact stuck again while sliding (the test's design rules it out)

  // The rates, and f_n, the slip and the overlap at y.
  State rate(const State& y, bool sliding, double& fn, double& overlap) const {
    const double dx = y[5] - y[0], dy = y[6] - y[1], R = std::hypot(dx, dy);
    const double nx = dx / R, ny = dy / R, tx = -ny, ty = nx;
    overlap = 2 * kR - R;
    const double a = kR - overlap / 2;
    const double ux = y[2] - y[7], uy = y[3] - y[8];
    const double vn = ux * nx + uy * ny, vs = ux * tx + uy * ty + a * y[4] + a * y[9];
    fn = std::max(p.kn * std::max(overlap, 0.0) + p.eta_n * vn, 0.0);
    const double fs = sliding ? std::copysign(p.mu * fn, y[10]) : y[10] + p.eta_s * vs;
    const double fx = -fn * nx - fs * tx, fy = -fn * ny - fs * ty;  // on disc 0
    return {y[2], y[3], fx / kMass, fy / kMass, -a * fs / kInertia,
            y[7], y[8], -fx / kMass, -fy / kMass, -a * fs / kInertia, p.ks * vs};
  }
  State rk4(const State& y, double h, bool sliding) const {
    double fn, ov;
    const auto add = [](const State& a, const State& b, double s) {
      State c;
      for (std::size_t k = 0; k < a.size(); ++k) c[k] = a[k] + s * b[k];
      return c;
    };
    const State k1 = rate(y, sliding, fn, ov), k2 = rate(add(y, k1, h / 2), sliding, fn, ov);
    const State k3 = rate(add(y, k2, h / 2), sliding, fn, ov), k4 = rate(add(y, k3, h), sliding, fn, ov);
    State out;
    for (std::size_t k = 0; k < y.size(); ++k) out[k] = y[k] + h / 6 * (k1[k] + 2 * k2[k] + 2 * k3[k] + k4[k]);
    return out;
  }
  double fn_at(const State& y) const {
    double fn, ov;
    rate(y, false, fn, ov);
    return fn;
  }
  // The state once the discs are apart (the velocities are final: free flight), from the touch.
  State after(double h) {
    State y{-kR, 0, kVn / 2, kVt / 2, 0, kR, 0, -kVn / 2, -kVt / 2, 0, 0};
    bool sliding = false;
    for (long step = 0; step < 100000000; ++step) {
      State z = rk4(y, h, sliding);
      double fn, ov;
      rate(z, sliding, fn, ov);
      if (!sliding && std::abs(z[10]) > p.mu * fn) {  // the slip starts inside the step: where, exactly
        double lo = 0, hi = h;
        for (int it = 0; it < 200 && hi - lo > 1e-15 * h; ++it) {
          const double mid = 0.5 * (lo + hi);
          const State m = rk4(y, mid, false);
          (std::abs(m[10]) > p.mu * fn_at(m) ? hi : lo) = mid;
        }
        z = rk4(y, hi, false);
        sliding = true;
      }
      if (sliding) {  // the spring held at the cap; below it the contact would stick again
        const double cap = p.mu * fn_at(z);
        if (std::abs(z[10]) < cap * (1 - 1e-12) && fn_at(z) > 0) restuck = true;
        z[10] = std::copysign(cap, z[10]);
      }
      y = z;
      if (ov < 0) return y;  // apart (f_n went to 0 before: no force since)
    }
    return y;
  }
};

// The engine's run of the same collision: the touch `phase` of a step after a step edge; the
// spin of disc 0 once apart. forget_fn: the deliberately wrong scheme, the kept f_n dropped
// before every step (the cap at the step's start unknown: no slip correction between discs).
double engine_spin(double dt, double phase, bool forget_fn) {
  World w = make_world(oblique_props(), shared_law(), Scheme::velocity_verlet_onset, dt);
  const double T = (3 + phase) * dt;  // free flight to the touch
  w.discs.add(-kR - T * kVn / 2, -T * kVt / 2, kR, kRho, 0);
  w.discs.add(kR + T * kVn / 2, T * kVt / 2, kR, kRho, 0);
  w.discs.vx = {kVn / 2, -kVn / 2};
  w.discs.vy = {kVt / 2, -kVt / 2};
  w.init();
  const long steps = static_cast<long>((T + 1.5 * contact_time()) / dt);
  for (long s = 0; s < steps; ++s) {
    if (forget_fn) w.onset_normals.clear();
    w.step();
  }
  const double dx = w.discs.x[1] - w.discs.x[0], dy = w.discs.y[1] - w.discs.y[0];
  EXPECT_GT(std::hypot(dx, dy), 2 * kR) << "the discs must be apart at the end";
  return w.discs.omega[0];
}

// The order of the RMS error (over touch phases) of the final spin: the least-squares slope of
// log error against log dt.
double spin_order(double w_ref, bool forget_fn, const char* label) {
  const int divisions[] = {50, 100, 200, 400};
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (int n : divisions) {
    const double dt = contact_time() / n;
    const int phases = 8;
    double sum = 0;
    for (int k = 0; k < phases; ++k) {
      const double err = engine_spin(dt, (k + 0.5) / phases, forget_fn) / w_ref - 1;
      sum += err * err;
    }
    const double rms = std::sqrt(sum / phases);
    std::printf("%s: dt = t_c / %d: rms relative error of the spin %.3e\n", label, n, rms);
    const double x = std::log(dt), yv = std::log(rms);
    sx += x; sy += yv; sxx += x * x; sxy += x * yv;
  }
  const double m = 4;
  return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

}  // namespace

// The reference itself: converged (a finer step changes the spin by far less than the engine's
// smallest error), and the collision it describes is the one intended (it slides to the end).
TEST(OnsetSlip, ReferenceConvergesAndSlides) {
  Reference a, b;
  const double w1 = a.after(contact_time() / 2e4)[4], w2 = b.after(contact_time() / 4e4)[4];
  EXPECT_FALSE(a.restuck);
  EXPECT_FALSE(b.restuck);
  EXPECT_LT(std::abs(w1 / w2 - 1), 1e-9);
  EXPECT_LT(w1, -1.0) << "a clear spin (rad/s) from the tangential impulse";
}

// Oblique disc-disc collision, sticking for about t_c / 8 and then sliding: the final spin
// converges with order 2 (slip correction from the kept f_n); with the f_n dropped before every
// step it is first order.
TEST(OnsetSlip, ObliqueDiscDiscSpinIsSecondOrder) {
  Reference ref;
  const double w_ref = ref.after(contact_time() / 2e4)[4];
  ASSERT_FALSE(ref.restuck);
  const double p_on = spin_order(w_ref, false, "onset");
  const double p_wrong = spin_order(w_ref, true, "onset, f_n dropped");
  std::printf("oblique disc-disc spin: reference %.17g rad/s; order %.2f; with the kept f_n dropped %.2f\n", w_ref,
              p_on, p_wrong);
  EXPECT_GT(p_on, 1.8) << "the slip onset between discs must be second order";
  EXPECT_LT(p_on, 2.5);
  EXPECT_LT(p_wrong, 1.3) << "without the cap at the step's start the slip onset is first order";
}

namespace {

// The 10k-disc lattice silo under the shared law as its first contacts form, the discs launched
// sideways so that contacts slide (a lattice falling straight down hardly shears its contacts).
void build_sliding_silo(World& w) {
  SceneOverrides ov;
  ov.scheme = "velocity_verlet_onset";
  ov.dt = 2e-5;
  ov.force_dt = true;
  ov.sets = {"contact.normal_spring=overlap", "contact.no_tension=total", "contact.friction_cap=total",
             "contact.lever_arm=contact_point"};
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov);
  spec.threads = 1;
  build_world(spec, w);
  for (std::size_t i = 0; i < w.discs.size(); ++i) {
    w.discs.vx[i] = 40.0 * std::sin(0.7 * static_cast<double>(i));
    w.discs.omega[i] = 30.0 * std::cos(1.3 * static_cast<double>(i));
  }
}

// The kept f_n by the discs' ids, to compare across removals and re-sorts.
std::vector<std::array<double, 3>> normals_by_id(const World& w) {
  std::vector<std::array<double, 3>> out;
  for (const PairNormals::Record& q : w.onset_normals.records()) {
    const int a = w.discs.id_at(q.i()), b = w.discs.id_at(q.j());
    out.push_back({static_cast<double>(std::min(a, b)), static_cast<double>(std::max(a, b)), q.fn});
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// A run split through a saved state equals the run in one piece: the kept f_n travel in the state
// file. Dropping them at the split (the deliberately wrong resume) changes the bits: slips start
// in the resumed part.
TEST(OnsetSlip, ResumeThroughSavedStateKeepsTheNormalForces) {
  World b, c;
  build_sliding_silo(b);
  build_sliding_silo(c);
  const long steps = 300, split = 157;
  for (long s = 0; s < steps; ++s) b.step();
  for (long s = 0; s < split; ++s) c.step();
  ASSERT_GT(c.onset_normals.size(), 100u) << "contacts must have formed";
  const std::string path = ::testing::TempDir() + "/onset_slip_split.state";
  save_state(c, path);
  World d, e;
  build_sliding_silo(d);
  build_sliding_silo(e);
  load_state(d, path);
  load_state(e, path);
  std::remove(path.c_str());
  EXPECT_EQ(normals_by_id(c), normals_by_id(d));
  e.onset_normals.clear();
  for (long s = split; s < steps; ++s) d.step();
  for (long s = split; s < steps; ++s) e.step();
  ASSERT_EQ(b.discs.size(), d.discs.size());
  EXPECT_EQ(state_hash(b.discs), state_hash(d.discs));
  EXPECT_NE(state_hash(b.discs), state_hash(e.discs)) << "no slip correction in the resumed part: the test sees nothing";
}

// Removals and re-sorts carry each pair's f_n with its discs; a scheme other than the onset one,
// or the elastic cap, keeps none.
TEST(OnsetSlip, RemovalsAndResortsCarryTheNormalForces) {
  World w;
  build_sliding_silo(w);
  for (int s = 0; s < 200; ++s) w.step();
  const auto before = normals_by_id(w);
  ASSERT_GT(before.size(), 100u);
  w.resort_discs();
  ASSERT_EQ(w.resorts, 1) << "the test needs a re-sort";
  EXPECT_EQ(normals_by_id(w), before);
  RemovedDiscs gone;
  for (int i = 0; i < static_cast<int>(w.discs.size()); i += 7) gone.sorted.push_back(i);
  std::vector<int> gone_ids;
  for (int i : gone.sorted) gone_ids.push_back(w.discs.id_at(i));
  w.remove_discs(gone);
  std::vector<std::array<double, 3>> kept;
  for (const auto& q : before)
    if (std::find(gone_ids.begin(), gone_ids.end(), static_cast<int>(q[0])) == gone_ids.end() &&
        std::find(gone_ids.begin(), gone_ids.end(), static_cast<int>(q[1])) == gone_ids.end())
      kept.push_back(q);
  EXPECT_EQ(normals_by_id(w), kept);
  for (int s = 0; s < 20; ++s) w.step();  // and the run goes on over them
  EXPECT_TRUE(w.all_finite());
  for (const char* cap : {"elastic", "total"})
    for (const char* scheme : {"velocity_verlet", "velocity_verlet_onset"}) {
      if (std::string(cap) == "total" && std::string(scheme) == "velocity_verlet_onset") continue;
      SceneOverrides ov;
      ov.scheme = scheme;
      ov.dt = 2e-5;
      ov.force_dt = true;
      ov.sets = {"contact.normal_spring=overlap", "contact.no_tension=total", std::string("contact.friction_cap=") + cap};
      World o;
      build_world(load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov), o);
      for (int s = 0; s < 50; ++s) o.step();
      EXPECT_FALSE(o.onset_normals.allocated()) << scheme << ", friction_cap " << cap;
    }
}

// A state file of format version 6 (no kept f_n: the last array of version 7) loads, without
// them; one with another version is refused.
TEST(OnsetSlip, StateFilesOfVersion6LoadWithoutTheNormalForces) {
  World c;
  build_sliding_silo(c);
  for (int s = 0; s < 100; ++s) c.step();
  ASSERT_GT(c.onset_normals.size(), 0u);
  const std::string path = ::testing::TempDir() + "/onset_slip_v6.state";
  save_state(c, path);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::size_t tail = 8 + c.onset_normals.size() * sizeof(PairNormals::Record);
  ASSERT_EQ(bytes.substr(0, 8), "DEMSTAT7");
  const auto write = [&](const std::string& b) { std::ofstream(path, std::ios::binary) << b; };
  std::string v6 = bytes.substr(0, bytes.size() - tail);
  v6[7] = '6';
  write(v6);
  World d;
  build_sliding_silo(d);
  load_state(d, path);
  EXPECT_EQ(d.onset_normals.size(), 0u);
  EXPECT_EQ(state_hash(c.discs), state_hash(d.discs));
  v6[7] = '5';
  write(v6);
  World e;
  build_sliding_silo(e);
  EXPECT_THROW(load_state(e, path), std::runtime_error);
  std::remove(path.c_str());
}
