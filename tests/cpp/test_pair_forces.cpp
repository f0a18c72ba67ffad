// The recorded pair totals (World::pair_forces): a force pass records f_n and f_s of the touching
// pairs only when asked, recording does not change a step's arithmetic, and the record holds the
// forces the pass applied: rebuilding every disc's resultant from the record, the wall contacts
// and gravity (eq. 15) gives the resultant the engine summed.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "discharge.hpp"
#include "scene.hpp"
#include "world.hpp"

namespace dem {
namespace {

// The 10k-disc lattice silo: its discs settle into contact at once, with walls.
World settle(int threads, long steps, bool record_every_step) {
  SceneOverrides ov;
  ov.scheme = "velocity_verlet";  // the resultants stay those of the pass's positions
  ov.dt = 5e-5;
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov);
  spec.threads = threads;
  World w;
  build_world(spec, w);
  w.record_pair_forces = record_every_step;
  for (long s = 0; s < steps; ++s) w.step();
  return w;
}

TEST(PairForces, RecordedOnlyWhenAskedAndWithoutChangingTheStep) {
  for (int threads : {1, 2}) {
    World plain = settle(threads, 300, false);
    EXPECT_FALSE(plain.pair_forces_current());
    EXPECT_TRUE(plain.pair_forces.empty()) << "a run that asks for nothing records nothing";
    World rec = settle(threads, 300, true);
    ASSERT_TRUE(rec.pair_forces_current());
    EXPECT_FALSE(rec.pair_forces.empty());
    ASSERT_EQ(plain.discs.size(), rec.discs.size());
    for (std::size_t i = 0; i < plain.discs.size(); ++i) {
      ASSERT_EQ(plain.discs.x[i], rec.discs.x[i]) << threads << " threads, disc " << i;
      ASSERT_EQ(plain.discs.vy[i], rec.discs.vy[i]) << threads << " threads, disc " << i;
    }
    for (std::size_t k = 1; k < rec.pair_forces.size(); ++k) {  // sorted by (i, j), as the pair list
      const PairForce &a = rec.pair_forces[k - 1], &b = rec.pair_forces[k];
      ASSERT_TRUE(a.i < b.i || (a.i == b.i && a.j < b.j)) << threads << " threads, entry " << k;
    }
    // One more step without recording: the record is no longer this step's, and its memory is
    // given back (stale totals never sit beside a list build's scratch).
    rec.record_pair_forces = false;
    rec.step();
    EXPECT_FALSE(rec.pair_forces_current());
    EXPECT_EQ(rec.pair_forces.capacity(), 0u);
  }
}

TEST(PairForces, RecordRebuildsTheResultants) {
  for (int threads : {1, 2}) {
    World w = settle(threads, 700, false);
    w.record_pair_forces = true;
    w.step();
    ASSERT_TRUE(w.pair_forces_current());
    // Verlet: after the step the discs stand where the pass computed the forces, and fx, fy,
    // torque still hold its resultants (the closing half kick reads them).
    const Discs& d = w.discs;
    const std::size_t n = d.size();
    std::vector<double> fx(n), fy(n), tq(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      fx[i] = d.mass(i) * w.gx;
      fy[i] = d.mass(i) * w.gy;
    }
    long touching = 0;
    for (const PairForce& c : w.pair_forces) {
      const double dx = d.x[c.j] - d.x[c.i], dy = d.y[c.j] - d.y[c.i];
      const double R = std::hypot(dx, dy);
      ASSERT_LE(R, d.r(c.i) + d.r(c.j)) << "a recorded pair touches";
      const double nx = dx / R, ny = dy / R;
      const double ox = -c.fn * nx + c.fs * ny, oy = -c.fn * ny - c.fs * nx;  // (15a), (15b) on i
      fx[c.i] += ox; fy[c.i] += oy; tq[c.i] -= d.r(c.i) * c.fs;
      fx[c.j] -= ox; fy[c.j] -= oy; tq[c.j] -= d.r(c.j) * c.fs;
      touching += c.fn > 0;
    }
    for (const WallContact& c : w.neighbors.walls) {
      if (!c.touching) continue;
      fx[c.i] += -c.fn * c.nx + c.fs * c.ny;
      fy[c.i] += -c.fn * c.ny - c.fs * c.nx;
      tq[c.i] -= d.r(c.i) * c.fs;
    }
    EXPECT_GT(touching, static_cast<long>(n / 2)) << "the packing must be in contact";
    double scale = 0;
    for (std::size_t i = 0; i < n; ++i) scale = std::max(scale, std::abs(d.mass(i) * w.gy));
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_NEAR(fx[i], d.fx[i], 1e-9 * scale) << threads << " threads, disc " << i;
      ASSERT_NEAR(fy[i], d.fy[i], 1e-9 * scale) << threads << " threads, disc " << i;
      ASSERT_NEAR(tq[i], d.torque[i], 1e-9 * scale * d.r(i)) << threads << " threads, disc " << i;
    }
  }
}

TEST(PairForces, ArchSearchRefusesAStepWithoutRecord) {
  World w = settle(1, 50, false);
  EXPECT_THROW(find_arch(w, -1.0, 1.0, 0.0), std::logic_error);
}

}  // namespace
}  // namespace dem
