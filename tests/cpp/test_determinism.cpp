// Determinism: the same scene gives bit-identical results whatever the thread count. A hash of
// every disc's position, velocity and spin after N steps is compared with the hash stored here
// for 1 thread, and the 2-thread run must give it too; it changes only when the arithmetic of a
// step changes (then it must be re-recorded on purpose, with the reason in the commit). The scene
// settles 4500 discs from a loose start, so contacts form and break and the lists are rebuilt
// many times. (tests/python/test_thread_counts.py compares every output file of 1, 2 and 3
// threads on a 10k-disc fill and discharge.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "janssen_bin.hpp"
#include "scene/scene.hpp"
#include "physics/parallel.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

std::uint64_t state_hash(const Discs& d) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the bytes of the doubles
  auto mix = [&](const std::vector<double>& v) {
    for (double x : v) {
      unsigned char b[sizeof x];
      std::memcpy(b, &x, sizeof x);
      for (unsigned char c : b) h = (h ^ c) * 1099511628211ull;
    }
  };
  for (const auto* v : {&d.x, &d.y, &d.phi, &d.vx, &d.vy, &d.omega}) mix(*v);
  return h;
}

struct Outcome {
  std::uint64_t hash;
  long rebuilds;
  std::size_t pairs;
  std::size_t capacity;  // of the pair list
};

Outcome run(int threads, bool paper_law, long steps) {
  SceneSpec spec = dem::testing::janssen_bin(threads);
  spec.rotation_angle = true;  // phi is in the hash (stored before the angle became an option)
  if (paper_law) {  // the paper's law and scheme (all defaults) on the same packing
    spec.contact = ContactOptions{};
    spec.scheme = Scheme::paper_eq19;
  }
  World w;
  build_world(spec, w);
  for (long s = 0; s < steps; ++s) w.step();
  return {state_hash(w.discs), w.neighbors.rebuilds, w.neighbors.pairs.size(), w.neighbors.pairs.capacity()};
}

constexpr long kSteps = 1500;

TEST(Determinism, SameThreadCountSameBits) {
  for (int threads : {1, 2}) {
    const Outcome a = run(threads, false, kSteps), b = run(threads, false, kSteps);
    EXPECT_EQ(a.hash, b.hash) << threads << " threads";
    EXPECT_GT(a.rebuilds, 3) << "the scene must exercise list rebuilds";
  }
}

TEST(Determinism, StoredHashesAnyThreadCount) {
  // Recorded with this engine (gcc 12, -O3 Release and the ASan build agree: -ffp-contract=off).
  const Outcome s1 = run(1, false, kSteps), s2 = run(2, false, kSteps);
  const Outcome p1 = run(1, true, kSteps), p2 = run(2, true, kSteps);
  std::printf("hashes: shared law 1 thread %016llx, 2 threads %016llx; paper law 1 thread %016llx, 2 threads %016llx\n",
              static_cast<unsigned long long>(s1.hash), static_cast<unsigned long long>(s2.hash),
              static_cast<unsigned long long>(p1.hash), static_cast<unsigned long long>(p2.hash));
  EXPECT_EQ(s1.hash, 0xb2a18727a1340047ull);
  EXPECT_EQ(s2.hash, 0xb2a18727a1340047ull);
  EXPECT_EQ(p1.hash, 0x6b1aaadf2b1f1e05ull);
  EXPECT_EQ(p2.hash, 0x6b1aaadf2b1f1e05ull);
  // The lists do not depend on the thread count (blocks concatenate in order).
  EXPECT_EQ(s1.pairs, s2.pairs);
  EXPECT_EQ(s1.rebuilds, s2.rebuilds);
}

// The 10k-disc lattice silo as its columns close (400 steps: some 9000 touching pairs, a hundred
// of them across each edge of the threads' blocks), every 50th pass recorded: 1, 2 and 3 threads
// give the same discs and the same recorded pair totals.
TEST(Determinism, CrossPairsAnyThreadCount) {
  const SceneSpec base = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml");
  std::uint64_t hash1 = 0;
  std::vector<PairForce> totals1;
  for (int threads : {1, 2, 3}) {
    SceneSpec spec = base;
    spec.threads = threads;
    World w;
    build_world(spec, w);
    for (int s = 1; s <= 400; ++s) {
      w.record_pair_forces = s % 50 == 0;
      w.step();
    }
    const std::vector<PairForce> totals = w.recorded_pairs();
    ASSERT_GT(totals.size(), 5000u);
    if (threads == 1) {
      hash1 = state_hash(w.discs);
      totals1 = totals;
      continue;
    }
    EXPECT_EQ(state_hash(w.discs), hash1) << threads << " threads";
    ASSERT_EQ(totals.size(), totals1.size()) << threads << " threads";
    bool same = true;
    for (std::size_t k = 0; k < totals.size(); ++k)
      same = same && totals[k].i == totals1[k].i && totals[k].j == totals1[k].j &&
             std::memcmp(&totals[k].fn, &totals1[k].fn, sizeof(double)) == 0 &&
             std::memcmp(&totals[k].fs, &totals1[k].fs, sizeof(double)) == 0;
    EXPECT_TRUE(same) << threads << " threads: other recorded totals";
    ASSERT_EQ(w.force_blocks.size(), static_cast<std::size_t>(threads) + 1);
    for (int t = 1; t < threads; ++t) {
      const int edge = w.force_blocks[t];
      EXPECT_GT(std::count_if(totals.begin(), totals.end(), [&](const PairForce& c) { return c.i < edge && c.j >= edge; }), 20)
          << threads << " threads: too few touching pairs across a block's edge for the test to see their order";
    }
  }
}

// Sums over the discs (kinetic and potential energy, the rest measure) have blocks of their own,
// not one a thread: every thread count gives the same bits, also past one block.
TEST(Determinism, SumsAnyThreadCount) {
  const long n = 5 * kSumBlock + 123;
  const auto f = [](long i) { return 1.0 / static_cast<double>(i + 1) + 1e-3 * std::sin(static_cast<double>(i)); };
  const double one = parallel_sum(n, 1, f);
  EXPECT_EQ(one, parallel_sum(n, 2, f));
  EXPECT_EQ(one, parallel_sum(n, 3, f));
  EXPECT_EQ(one, parallel_sum(n, 7, f));
  double plain = 0;
  for (long i = 0; i < kSumBlock; ++i) plain += f(i);
  EXPECT_EQ(plain, parallel_sum(kSumBlock, 2, f)) << "one block: the plain loop";
}

TEST(Memory, PairListCostsAboutItsLengthNotDouble) {
  // Lists are sized from the last build plus a margin, and the first build counts first
  // (neighbors.cpp), never by push_back doubling, which leaves up to 2x the list's bytes in the
  // list and in the scratch of the next build (at 1M discs, ~120 MB each).
  // Lattices of 5000, 7000 and 10000 discs: one list at least lies far enough past a power of two
  // (7000 discs, about 21k pairs) that doubling would exceed the bound.
  const SceneSpec full = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml");
  bool past_power = false;
  for (std::size_t count : {5000u, 7000u, 10000u})
  for (int threads : {1, 2}) {
    SceneSpec spec = full;
    spec.discs.resize(std::min(count, spec.discs.size()));
    spec.threads = threads;
    World w;
    build_world(spec, w);
    const std::size_t n0 = w.neighbors.pairs.size();
    EXPECT_LE(w.neighbors.pairs.capacity(), n0 + n0 / 8 + 1024) << threads << " threads, first build";
    for (int s = 0; s < 20; ++s) {
      if (s % 5 == 0) w.neighbors.invalidate();  // rebuilds from the old lists
      w.step();
    }
    const std::size_t n = w.neighbors.pairs.size();
    std::size_t pow2 = 1;
    while (pow2 < n) pow2 *= 2;
    past_power = past_power || pow2 > n + n / 8 + 1024;
    ASSERT_GE(w.neighbors.rebuilds, 5);
    EXPECT_LE(w.neighbors.pairs.capacity(), n + n / 8 + 1024) << count << " discs, " << threads << " threads";
  }
  EXPECT_TRUE(past_power) << "no list size where doubling would show: the test cannot fail";
}

}  // namespace
}  // namespace dem
