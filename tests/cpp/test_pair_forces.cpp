// The recorded pair totals (World::pair_totals): a force pass records f_n and f_s of the touching
// pairs only when asked, recording does not change a step's arithmetic, and the record holds the
// forces the pass applied: rebuilding every disc's resultant from the record, the wall contacts
// and gravity (eq. 15) gives the resultant the engine summed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "measures/arch.hpp"
#include "physics/pair_totals.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

// The 10k-disc lattice silo: its discs settle into contact at once, with walls.
World settle(int threads, long steps, bool record_every_step, const char* scheme = "velocity_verlet") {
  SceneOverrides ov;
  ov.scheme = scheme;  // Verlet: the resultants stay those of the pass's positions
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
    EXPECT_TRUE(plain.pair_totals.empty()) << "a run that asks for nothing records nothing";
    World rec = settle(threads, 300, true);
    ASSERT_TRUE(rec.pair_forces_current());
    EXPECT_FALSE(rec.pair_totals.empty());
    ASSERT_EQ(plain.discs.size(), rec.discs.size());
    for (std::size_t i = 0; i < plain.discs.size(); ++i) {
      ASSERT_EQ(plain.discs.x[i], rec.discs.x[i]) << threads << " threads, disc " << i;
      ASSERT_EQ(plain.discs.vy[i], rec.discs.vy[i]) << threads << " threads, disc " << i;
    }
    const std::vector<PairForce> recs = rec.recorded_pairs();
    for (std::size_t k = 1; k < recs.size(); ++k) {  // sorted by (i, j), as the pair list
      const PairForce &a = recs[k - 1], &b = recs[k];
      ASSERT_TRUE(a.i < b.i || (a.i == b.i && a.j < b.j)) << threads << " threads, entry " << k;
    }
    // One more step without recording: the record is no longer this step's, and its memory is
    // given back (stale totals never sit beside a list build's scratch).
    rec.record_pair_forces = false;
    rec.step();
    EXPECT_FALSE(rec.pair_forces_current());
    EXPECT_FALSE(rec.pair_totals.allocated());
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
    for (const PairForce& c : w.recorded_pairs()) {
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

bool same(const PairForce& a, const PairForce& b) {
  return a.i == b.i && a.j == b.j && a.fn == b.fn && a.fs == b.fs;
}

// The totals of every list pair by a walk with one cursor (PairTotals::at), as explicit records.
std::vector<PairForce> walk(const World& w, std::size_t from = 0) {
  std::vector<PairForce> out;
  PairTotals::Cursor c;
  for (std::size_t p = from; p < w.neighbors.pairs.size(); ++p)
    if (const PairTotals::Force* f = w.pair_totals.at(w.neighbors.pairs, p, c))
      out.push_back(PairForce{w.neighbors.pairs[p].i, w.neighbors.pairs[p].j, f->fn, f->fs});
  return out;
}

// The two forms of the totals (bound: a bit over the pass's list; detached: with their (i, j))
// give the same records, the same totals pair by pair, and the same after removals.
TEST(PairTotals, BoundAndDetachedFormsAgreeAndFollowRemovals) {
  for (int threads : {1, 2}) {
    World w = settle(threads, 700, false);
    w.record_pair_forces = true;
    w.compute_forces_now();
    ASSERT_FALSE(w.pair_totals.detached());
    const std::vector<PairForce> rec = w.recorded_pairs();
    ASSERT_GT(rec.size(), 5000u) << "the packing must be in contact";
    // The records are the list's pairs that touch now (the pass ran at these positions), in order.
    std::size_t touching = 0;
    for (const PairContact& c : w.neighbors.pairs) {
      const double dx = w.discs.x[c.j] - w.discs.x[c.i], dy = w.discs.y[c.j] - w.discs.y[c.i];
      const double sum = w.discs.r(c.i) + w.discs.r(c.j);
      touching += dx * dx + dy * dy <= sum * sum;
    }
    ASSERT_EQ(rec.size(), touching);
    World detached = w;
    detached.pair_totals.detach(detached.neighbors.pairs);
    ASSERT_TRUE(detached.pair_totals.detached());
    for (const World* v : {&w, &detached}) {
      const std::vector<PairForce> all = v->recorded_pairs(), walked = walk(*v);
      ASSERT_EQ(all.size(), rec.size());
      ASSERT_EQ(walked.size(), rec.size());
      for (std::size_t k = 0; k < rec.size(); ++k) {
        ASSERT_TRUE(same(all[k], rec[k])) << threads << " threads, record " << k;
        ASSERT_TRUE(same(walked[k], rec[k])) << threads << " threads, record " << k;
      }
      // A walk from the middle of the list, on a fresh cursor, finds the same tail.
      const PairForce& half = rec[rec.size() / 2];  // a list place among the touching pairs
      const auto& pl = v->neighbors.pairs;
      const std::size_t mid = std::lower_bound(pl.begin(), pl.end(), half, [](const PairContact& c, const PairForce& q) {
                                return c.i < q.i || (c.i == q.i && c.j < q.j);
                              }) - pl.begin();
      const std::vector<PairForce> tail = walk(*v, mid);
      ASSERT_FALSE(tail.empty());
      ASSERT_TRUE(same(tail.back(), rec.back()));
      ASSERT_TRUE(same(tail.front(), rec[rec.size() - tail.size()]));
    }
    // Removals: every 7th disc and a run of 50. The records that stay are those of pairs of two
    // kept discs, renumbered by the discs kept below them (counted here, not by RemovedDiscs).
    RemovedDiscs gone;
    const int n = static_cast<int>(w.discs.size());
    for (int i = 0; i < n; ++i)
      if (i % 7 == 3 || (i >= 4000 && i < 4050)) gone.sorted.push_back(i);
    std::vector<int> renum(n);
    for (int i = 0, kept = 0, g = 0; i < n; ++i) {
      const bool out = g < static_cast<int>(gone.sorted.size()) && gone.sorted[g] == i;
      renum[i] = out ? -1 : kept;
      if (out) ++g;
      else ++kept;
    }
    std::vector<PairForce> want;
    for (const PairForce& q : rec)
      if (renum[q.i] >= 0 && renum[q.j] >= 0) want.push_back(PairForce{renum[q.i], renum[q.j], q.fn, q.fs});
    ASSERT_LT(want.size(), rec.size());
    for (World* v : {&w, &detached}) {
      const bool was_detached = v->pair_totals.detached();
      v->remove_discs(gone);
      EXPECT_EQ(v->pair_totals.detached(), was_detached) << "removals keep the form";
      const std::vector<PairForce> all = v->recorded_pairs(), walked = walk(*v);
      ASSERT_EQ(all.size(), want.size());
      ASSERT_EQ(walked.size(), want.size());
      for (std::size_t k = 0; k < want.size(); ++k) {
        ASSERT_TRUE(same(all[k], want[k])) << threads << " threads, detached " << was_detached << ", record " << k;
        ASSERT_TRUE(same(walked[k], want[k])) << threads << " threads, detached " << was_detached << ", record " << k;
      }
    }
  }
}

// Eqs. (18), (19) build the lists right after a step's fused force pass when a disc has gone
// past skin/2: the step's totals then leave the bits over the old list for their own (i, j). They
// are the totals of that pass either way: those of the same pass on a copy of the world before
// the step (the same positions, increments and history).
TEST(PairForces, StepTotalsSurviveTheListBuildThatFollowsThem) {
  for (const char* scheme : {"paper_eq19", "paper_eq18"}) {
    for (int threads : {1, 2}) {
      World w = settle(threads, 20, false, scheme);
      w.neighbors.skin = 0.02;  // [cm] a tenth of the scene's: builds every few steps
      w.neighbors.invalidate();
      int bound = 0, rebuilt = 0;
      for (int s = 0; s < 400 && (bound < 3 || rebuilt < 3); ++s) {
        World before = w;
        before.record_pair_forces = true;
        before.compute_forces_now();
        const std::vector<PairForce> want = before.recorded_pairs();
        const long builds = w.neighbors.rebuilds + (w.neighbors.stale(w.discs) ? 1 : 0);  // one before the pass
        w.record_pair_forces = true;
        w.step();
        ASSERT_TRUE(w.pair_forces_current());
        const bool built = w.neighbors.rebuilds > builds;  // after the pass
        EXPECT_EQ(w.pair_totals.detached(), built) << scheme << ", step " << s;
        (built ? rebuilt : bound) += 1;
        const std::vector<PairForce> got = w.recorded_pairs(), walked = walk(w);
        ASSERT_EQ(got.size(), want.size()) << scheme << ", " << threads << " threads, step " << s;
        for (std::size_t k = 0; k < want.size(); ++k) ASSERT_TRUE(same(got[k], want[k])) << scheme << ", step " << s;
        // The walk over the new list finds the recorded pairs it still has, with their totals.
        std::size_t r = 0;
        for (const PairForce& q : walked) {
          while (r < got.size() && (got[r].i < q.i || (got[r].i == q.i && got[r].j < q.j))) ++r;
          ASSERT_LT(r, got.size());
          ASSERT_TRUE(same(got[r], q));
        }
      }
      EXPECT_GE(bound, 3) << scheme << ": steps without a build after the pass";
      EXPECT_GE(rebuilt, 3) << scheme << ": steps with a build after the pass";
    }
  }
}

TEST(PairForces, ArchSearchRefusesAStepWithoutRecord) {
  World w = settle(1, 50, false);
  EXPECT_THROW(find_arch(w, -1.0, 1.0, 0.0), std::logic_error);
}

}  // namespace
}  // namespace dem
