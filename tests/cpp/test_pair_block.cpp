// The pair stage by blocks (World::pair_contacts): on a dense, jittered packing with random history,
// where pairs touch, slide, go slack and come apart side by side, the forces and the new history
// are those of the law applied pair by pair (eqs. 3-15, written out here), for every option of
// the law and for 1 and 2 threads, and so are the recorded totals of an output step's pass (in
// exactly sized storage); and the law's AVX2 and SSE2 versions give the same bits.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "physics/contact_law.hpp"
#include "helpers.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

// 80 x 80 discs of radius 1 cm on a triangular lattice 2 % tighter than touching, each moved by
// up to 0.03 cm: most neighbours overlap, some are apart. Random velocities (the increments of
// eq. 18 are v dt) and random history, large enough for the Coulomb cap and for tension.
World dense_world(ContactOptions opt, int threads, unsigned seed) {
  PairProps p = testing::linear(9.45e7, 0.3, 4.16, 0.577, 2.36e7, 2.0e4);
  World w = testing::make_world(p, opt, Scheme::paper_eq18, 1e-4, -980.0);
  w.threads = threads;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.03, 0.03), speed(-5.0, 5.0);
  const double a = 1.96;  // lattice spacing [cm]
  for (int r = 0; r < 80; ++r)
    for (int c = 0; c < 80; ++c)
      w.discs.add(c * a + (r % 2) * 0.5 * a + jitter(rng), r * a * std::sqrt(0.75) + jitter(rng), 1.0, 2.65, 0);
  for (std::size_t i = 0; i < w.discs.size(); ++i) {
    w.discs.vx[i] = speed(rng);
    w.discs.vy[i] = speed(rng);
    w.discs.omega[i] = speed(rng);
  }
  w.prepare();
  std::uniform_real_distribution<double> en(-2e5, 4e6), es(-3e6, 3e6);
  for (PairContact& c : w.neighbors.pairs) {
    c.en = en(rng);
    c.es = es(rng);
  }
  return w;
}

struct Result {
  std::vector<double> fx, fy, tq, en, es;
  std::vector<PairForce> totals;  // the touching pairs' f_n, f_s, in list order
};

Result forces_of(World w, int width = World::vector_width) {  // a copy: each call starts from the same history
  w.set_vector_width(width);
  w.record_pair_forces = true;
  w.compute_forces_now();
  Result r{w.discs.fx, w.discs.fy, w.discs.torque, {}, {}, w.recorded_pairs()};
  EXPECT_EQ(w.pair_totals.capacity(), w.pair_totals.size()) << "the recorded totals are sized exactly";
  EXPECT_FALSE(w.pair_totals.detached()) << "a pass's totals are bound to its list";
  for (const PairContact& c : w.neighbors.pairs) {
    r.en.push_back(c.en);
    r.es.push_back(c.es);
  }
  return r;
}

// Eqs. (3)-(15) pair by pair, in list order, from the same state: the reference.
template <NormalSpring NS, NoTension NT, FrictionCap FC>
Result by_pairs(World w) {
  const Discs& d = w.discs;
  const std::size_t n = d.size();
  Result r{std::vector<double>(n), std::vector<double>(n), std::vector<double>(n, 0.0), {}, {}, {}};
  for (std::size_t i = 0; i < n; ++i) {
    r.fx[i] = d.mass(i) * w.gx;
    r.fy[i] = d.mass(i) * w.gy;
  }
  for (PairContact& c : w.neighbors.pairs) {
    const int i = c.i, j = c.j;
    const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
    const double R = std::sqrt(dx * dx + dy * dy);
    double fn = 0, fs = 0;
    if (R > d.r(i) + d.r(j)) {  // (3)
      c.en = c.es = 0;
    } else {
      const double nx = dx / R, ny = dy / R;  // (4)
      const double ddx = (d.vx[i] - d.vx[j]) * w.dt, ddy = (d.vy[i] - d.vy[j]) * w.dt;
      const double du_n = ddx * nx + ddy * ny;                                                  // (5a)
      const double overlap = d.r(i) + d.r(j) - R;
      // The lever arms: r, or r - overlap/2 (lever_arm = contact_point)
      const bool mid = w.options.lever_arm == LeverArm::contact_point;
      const double ai = mid ? d.r(i) - overlap / 2 : d.r(i), aj = mid ? d.r(j) - overlap / 2 : d.r(j);
      const double du_s = -ddx * ny + ddy * nx + (ai * d.omega[i] + aj * d.omega[j]) * w.dt;  // (5b)
      contact_law<NS, NT, FC>(w.pair(0, 0), overlap, du_n, du_s, 1.0 / w.dt, c.en, c.es, fn, fs);
      const double fx = -fn * nx + fs * ny, fy = -fn * ny - fs * nx;  // (15a), (15b)
      r.fx[i] += fx; r.fy[i] += fy; r.tq[i] -= ai * fs;                // (15c)
      r.fx[j] -= fx; r.fy[j] -= fy; r.tq[j] -= aj * fs;
      r.totals.push_back({i, j, fn, fs});
    }
  }
  for (const PairContact& c : w.neighbors.pairs) {
    r.en.push_back(c.en);
    r.es.push_back(c.es);
  }
  return r;
}

Result reference(const World& w) {
  const ContactOptions o = w.options;
#define DEM_REF(NS, NT, FC)                                                                                   \
  if (o.normal_spring == NormalSpring::NS && o.no_tension == NoTension::NT && o.friction_cap == FrictionCap::FC) \
    return by_pairs<NormalSpring::NS, NoTension::NT, FrictionCap::FC>(w);
  DEM_REF(incremental, elastic, elastic) DEM_REF(incremental, elastic, total)
  DEM_REF(incremental, total, elastic) DEM_REF(incremental, total, total)
  DEM_REF(incremental, overlap, elastic) DEM_REF(incremental, overlap, total)
  DEM_REF(overlap, elastic, elastic) DEM_REF(overlap, elastic, total)
  DEM_REF(overlap, total, elastic) DEM_REF(overlap, total, total)
  DEM_REF(overlap, overlap, elastic) DEM_REF(overlap, overlap, total)
#undef DEM_REF
  ADD_FAILURE() << "no reference for these options";
  return {};
}

std::vector<ContactOptions> all_options() {
  std::vector<ContactOptions> v;
  for (NormalSpring ns : {NormalSpring::incremental, NormalSpring::overlap})
    for (NoTension nt : {NoTension::elastic, NoTension::total, NoTension::overlap})
      for (FrictionCap fc : {FrictionCap::elastic, FrictionCap::total})
        for (LeverArm la : {LeverArm::radius, LeverArm::contact_point}) v.push_back({ns, nt, fc, la});
  return v;
}

TEST(PairBlock, ForcesAndHistoryAreThoseOfThePairByPairLaw) {
  for (const ContactOptions& o : all_options())
    for (int threads : {1, 2}) {
      const World w = dense_world(o, threads, 7);
      ASSERT_EQ(w.threads_for(static_cast<int>(w.discs.size())), threads);
      const Result got = forces_of(w), want = reference(w);
      ASSERT_EQ(got.en.size(), want.en.size());
      // The mix the blocks must get right: touching, apart, sliding and slack pairs.
      std::size_t touching = 0, apart = 0, sliding = 0;
      for (std::size_t p = 0; p < want.en.size(); ++p) {
        const bool zero = want.en[p] == 0 && want.es[p] == 0;
        apart += zero;
        touching += !zero;
        sliding += !zero && std::abs(std::abs(want.es[p]) - 0.577 * want.en[p]) < 1e-9 * want.en[p];
      }
      EXPECT_GT(touching, 5000u);
      EXPECT_GT(apart, 500u);
      if (o.friction_cap == FrictionCap::elastic) {
        EXPECT_GT(sliding, 100u);
      }
      const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-9 * (1.0 + std::abs(b)); };
      std::size_t bad = 0;
      for (std::size_t p = 0; p < want.en.size(); ++p) bad += !near(got.en[p], want.en[p]) || !near(got.es[p], want.es[p]);
      ASSERT_EQ(got.totals.size(), want.totals.size());
      for (std::size_t k = 0; k < want.totals.size(); ++k) {
        const PairForce &g = got.totals[k], &f = want.totals[k];
        bad += g.i != f.i || g.j != f.j || !near(g.fn, f.fn) || !near(g.fs, f.fs);
      }
      // Resultants: sums of forces of order 1e6 dyn; a 2-thread pass adds the reactions on
      // another block's discs later, so the last bits may differ.
      const auto close = [](double a, double b) { return std::abs(a - b) <= 1e-6 * (1.0 + std::abs(b)); };
      for (std::size_t i = 0; i < got.fx.size(); ++i)
        bad += !close(got.fx[i], want.fx[i]) || !close(got.fy[i], want.fy[i]) || !close(got.tq[i], want.tq[i]);
      EXPECT_EQ(bad, 0u) << to_string(o.normal_spring) << " / " << to_string(o.no_tension) << " / "
                         << to_string(o.friction_cap) << " / " << to_string(o.lever_arm) << ", " << threads << " threads";
    }
}

// Four pairs a vector (AVX2) and eight (AVX-512), where the processor has them, give the bits of
// two (SSE2): forces, history and recorded totals.
TEST(PairBlock, WideAndNarrowLawGiveTheSameBits) {
  if (World::cpu_vector_width() < 4) GTEST_SKIP() << "this processor has no AVX2: only the SSE2 law runs";
  for (const ContactOptions& o : all_options())
    for (int threads : {1, 2}) {
      const World w = dense_world(o, threads, 11);
      const Result narrow = forces_of(w, 2);
      for (int width : {4, 8}) {
        if (width > World::cpu_vector_width()) continue;
        const Result wide = forces_of(w, width);
        EXPECT_EQ(wide.fx, narrow.fx) << width;
        EXPECT_EQ(wide.fy, narrow.fy) << width;
        EXPECT_EQ(wide.tq, narrow.tq) << width;
        EXPECT_EQ(wide.en, narrow.en) << width;
        EXPECT_EQ(wide.es, narrow.es) << width;
        ASSERT_EQ(wide.totals.size(), narrow.totals.size());
        for (std::size_t k = 0; k < wide.totals.size(); ++k) {
          EXPECT_EQ(wide.totals[k].fn, narrow.totals[k].fn) << width;
          EXPECT_EQ(wide.totals[k].fs, narrow.totals[k].fs) << width;
        }
      }
    }
}

}  // namespace
}  // namespace dem
