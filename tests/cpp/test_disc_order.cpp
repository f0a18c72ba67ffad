// The discs put in cell order (World::resort_discs, disc_order.hpp): the rule's measure, the same
// physics as the discs in the user's order, the same bits at every thread count and through a
// saved state, and the outputs in the user's order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "helpers.hpp"
#include "janssen_bin.hpp"
#include "io/outputs.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"
#include "scene/scene.hpp"

using namespace dem;

namespace {

// The Janssen bin: 4500 discs in a 15 cm bin, a loose start listed row by row (the lattice-like
// order a fill has), which settles: contacts form within a few hundred steps.
SceneSpec janssen(int threads = 1) { return dem::testing::janssen_bin(threads); }

// The same fill in a seeded random order: a user's file listing the discs in any order.
SceneSpec shuffled(SceneSpec spec, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::shuffle(spec.discs.begin(), spec.discs.end(), rng);
  return spec;
}

// Disc k of the user's order (id k: no disc is removed here).
std::vector<std::size_t> user_order(const Discs& d) {
  std::vector<std::size_t> at(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) at[static_cast<std::size_t>(d.id_at(i))] = i;
  return at;
}

// Two runs side by side, `steps` steps each.
void step_both(World& a, World& b, long steps) {
  for (long s = 0; s < steps; ++s) {
    a.step();
    b.step();
  }
}

// The largest |x| or |y| difference of one disc in two runs of the same discs [cm].
double largest_position_gap(const Discs& a, const Discs& b) {
  const std::vector<std::size_t> ua = user_order(a), ub = user_order(b);
  double worst = 0;
  for (std::size_t k = 0; k < ua.size(); ++k) {
    worst = std::max(worst, std::abs(a.x[ua[k]] - b.x[ub[k]]));
    worst = std::max(worst, std::abs(a.y[ua[k]] - b.y[ub[k]]));
  }
  return worst;
}

std::uint64_t user_hash(const Discs& d) {  // FNV-1a of x, y, vx, vy, omega in the user's order
  std::uint64_t h = 1469598103934665603ull;
  const std::vector<std::size_t> at = user_order(d);
  for (const auto* v : {&d.x, &d.y, &d.vx, &d.vy, &d.omega})
    for (std::size_t k = 0; k < d.size(); ++k) {
      unsigned char b[sizeof(double)];
      std::memcpy(b, &(*v)[at[k]], sizeof b);
      for (unsigned char c : b) h = (h ^ c) * 1099511628211ull;
    }
  return h;
}

}  // namespace

long rows_of(const World& w) { return order_grid(w.discs, w.neighbors.skin, w.neighbors.min_cell).ny; }

TEST(DiscOrder, SpreadOfRowOrderAndRandomOrder) {
  // A row-by-row order: a disc's partners are in its row of cells or the next, so the mean gap
  // j - i is at most about one row of cells' discs (spread <= 1). A random order: the mean gap of
  // a random pair is (n + 1) / 3, a spread of rows (n + 1) / (3 n), about rows / 3. Measured
  // over the pairs in contact after 2000 steps (the bottom of the falling column has landed).
  World rows, random;
  SceneSpec a = janssen(), b = shuffled(janssen());
  a.disc_order = b.disc_order = DiscOrder::off;
  build_world(a, rows);
  build_world(b, random);
  EXPECT_EQ(disc_order_spread(random.neighbors.pairs, random.discs, rows_of(random)), 0.0)
      << "the loose start has no contact: no measure";
  for (long s = 0; s < 2000; ++s) {
    rows.step();
    random.step();
  }
  const long ny = rows_of(random);
  ASSERT_GT(ny, 30) << "a tall bin: many rows of cells";
  EXPECT_LT(disc_order_spread(rows.neighbors.pairs, rows.discs, rows_of(rows)), 1.0);
  const double s = disc_order_spread(random.neighbors.pairs, random.discs, ny);
  // k pairs in contact: a random pair's gap has mean n / 3 and standard deviation n / sqrt(18),
  // so their mean is within 4 standard errors, (4 / sqrt(2 k)) n / 3, but for 1 time in 10^4.
  long k = 0;
  for (const PairContact& p : random.neighbors.pairs) k += p.en != 0 || p.es != 0;
  ASSERT_GT(k, 5);
  EXPECT_NEAR(s, ny / 3.0, 4.0 / std::sqrt(2.0 * k) * ny / 3.0) << k << " pairs in contact";
  EXPECT_FALSE(disc_order_degraded(rows.neighbors.pairs, rows.discs, rows_of(rows)));
  EXPECT_TRUE(disc_order_degraded(random.neighbors.pairs, random.discs, ny));
  EXPECT_EQ(rows.resorts, 0);
  EXPECT_EQ(random.resorts, 0);
}

TEST(DiscOrder, CellOrderFollowsTheGrid) {
  // Seven discs of radius 0.25 with a skin of 0.5: cells of 2 r + skin = 1 cm over the extent
  // [0.1, 1.3] x [0.1, 1.3], 2 x 2 of them. Cells row-major from the lower left, by x within a
  // cell and by index at equal x: cell 0 holds discs 4 (x 0.1), 1 and 6 (x 0.3), cell 1 disc 2,
  // cell 2 discs 5 (x 0.15) and 3 (x 0.2), cell 3 disc 0. By index within a cell it would be
  // 1, 4, 6, 2, 3, 5, 0.
  Discs d;
  for (auto [x, y] : {std::pair{1.2, 1.1}, {0.3, 0.2}, {1.3, 0.1}, {0.2, 1.3}, {0.1, 0.3}, {0.15, 1.2}, {0.3, 0.9}})
    d.add(x, y, 0.25, 1.0, 0);
  const OrderGrid g = order_grid(d, 0.5, 0.0);  // cell 2 r + skin = 1 cm over [0.1, 1.3] x [0.1, 1.3]
  ASSERT_EQ(g.nx, 2);
  ASSERT_EQ(g.ny, 2);
  EXPECT_EQ(cell_order(d, g), (std::vector<int>{4, 1, 6, 2, 5, 3, 0}));
}

TEST(DiscOrder, ShuffledFillIsResortedOnceAndStaysInOrder) {
  World w, lattice;
  build_world(shuffled(janssen()), w);
  build_world(janssen(), lattice);
  EXPECT_EQ(w.resorts, 0) << "no contact yet: nothing to measure";
  for (long s = 0; s < 3000; ++s) {
    w.step();
    lattice.step();
  }
  EXPECT_EQ(w.resorts, 1) << "the first check with contacts finds the random order, once";
  EXPECT_EQ(lattice.resorts, 0) << "a row-by-row fill is never re-sorted";
  EXPECT_LE(disc_order_spread(w.neighbors.pairs, w.discs, rows_of(w)), 1.0);
  // The ids are the user's indices, each once.
  std::vector<int> ids(w.discs.id.begin(), w.discs.id.end());
  std::sort(ids.begin(), ids.end());
  ASSERT_EQ(ids.size(), w.discs.size());
  for (std::size_t k = 0; k < ids.size(); ++k) ASSERT_EQ(ids[k], static_cast<int>(k));
}

TEST(DiscOrder, FilePackingIsResortedAtStepZero) {
  // A dense packing read from a file in a random order, run with the paper's law: its discs
  // overlap (a triangular lattice of spacing 0.99 d, 14 discs a row in the 15 cm bin) but its
  // incremental springs start without history. The rule counts the pairs that overlap, so the
  // first step re-sorts them; a rule that counted the pairs with history would see none until
  // the springs had grown, at the check of step 256.
  SceneSpec spec = janssen();
  const double r = 0.5, a = 0.99 * 2 * r;
  for (std::size_t k = 0; k < spec.discs.size(); ++k) {
    const long row = static_cast<long>(k / 14), col = static_cast<long>(k % 14);
    spec.discs[k].r = r;
    spec.discs[k].x = r + (static_cast<double>(col) + 0.5 * static_cast<double>(row % 2)) * a;
    spec.discs[k].y = r + static_cast<double>(row) * a * std::sqrt(3.0) / 2;
  }
  spec = shuffled(spec);
  spec.max_initial_overlap = 0.4;
  spec.scheme = Scheme::paper_eq19;
  spec.dt = 5e-5;
  spec.contact.normal_spring = NormalSpring::incremental;
  World w;
  build_world(spec, w);
  long overlapping = 0, with_history = 0;
  for (const PairContact& p : w.neighbors.pairs) {
    const double dx = w.discs.x[p.j] - w.discs.x[p.i], dy = w.discs.y[p.j] - w.discs.y[p.i];
    overlapping += std::hypot(dx, dy) <= w.discs.r(p.i) + w.discs.r(p.j);
    with_history += p.en != 0 || p.es != 0;
  }
  ASSERT_GT(overlapping, 1000) << "the settled packing rests on its overlaps";
  ASSERT_EQ(with_history, 0) << "the paper's springs start at zero";
  w.step();
  EXPECT_EQ(w.resorts, 1) << "re-sorted at step 0";
  EXPECT_LE(disc_order_spread(w.neighbors.pairs, w.discs, rows_of(w)), 1.0);
}

TEST(DiscOrder, SamePhysicsAsTheUserOrderToRoundOff) {
  // The re-sorted run computes the same contacts with the same history; only the order of each
  // disc's force terms differs (its pairs come in another list order), a round-off of 1e-16 of a
  // force a step, which the collisions of 2000 steps amplify but keep far below 1e-9 cm. A lost or
  // misplaced history (a pair, a wall contact or a reference position not following its discs)
  // moves discs by the elastic forces' effect, 1e-4 cm and more in 2000 steps.
  SceneSpec off = shuffled(janssen()), on = off;
  off.disc_order = DiscOrder::off;
  World a, b;
  build_world(off, a);
  build_world(on, b);
  long contacts = 0;
  step_both(a, b, 2500);
  ASSERT_EQ(b.resorts, 1);
  ASSERT_EQ(a.resorts, 0);
  for (const PairContact& p : b.neighbors.pairs) contacts += p.en != 0;
  ASSERT_GT(contacts, 10) << "the test needs pairs in contact (the column's foot has landed)";
  const double worst = largest_position_gap(a.discs, b.discs);
  std::printf("largest position difference, re-sorted vs user order: %.3g cm\n", worst);
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ(a.neighbors.rebuilds, b.neighbors.rebuilds);
}

TEST(DiscOrder, OnsetSchemeResortsToo) {
  // velocity_verlet_onset steps on its own path (World::step_onset): it checks the order too, and
  // the re-sort carries what it keeps (the pairs' f_n under the total cap), so the run stays the
  // user order's to round-off. Without the check it never re-sorts; a re-sort after v(t) is kept
  // would mix two discs' velocities in the dashpots' prediction.
  SceneSpec off = shuffled(janssen());
  off.scheme = Scheme::velocity_verlet_onset;
  off.dt = 1.3e-5;  // forced (janssen_bin): 1.6x the scheme's bound for the bin's smallest discs
  off.contact = dem::testing::shared_law();
  off.disc_order = DiscOrder::off;
  SceneSpec on = off;
  on.disc_order = DiscOrder::automatic;
  World a, b;
  build_world(off, a);
  build_world(on, b);
  step_both(a, b, 4000);
  ASSERT_EQ(a.resorts, 0);
  EXPECT_EQ(b.resorts, 1);
  ASSERT_GT(b.onset_normals.size(), 10u) << "the test needs pairs in contact under the total cap";
  const double worst = largest_position_gap(a.discs, b.discs);
  std::printf("largest position difference, onset scheme re-sorted vs user order: %.3g cm\n", worst);
  EXPECT_LT(worst, 1e-9);
}

TEST(DiscOrder, EveryThreadCountGivesTheBitsOfOne) {
  std::uint64_t h[2] = {};
  for (int t : {1, 2}) {
    World w;
    build_world(shuffled(janssen(t)), w);
    for (long s = 0; s < 2500; ++s) w.step();
    ASSERT_EQ(w.resorts, 1) << t << " threads";
    h[t - 1] = user_hash(w.discs);
  }
  EXPECT_EQ(h[0], h[1]);
}

TEST(DiscOrder, ResumedRunIsBitIdenticalAcrossAResort) {
  // The shuffled fill is re-sorted at the first check with contacts (the column lands after some
  // 700 steps): a state saved before it is resumed across the re-sort; one saved after it holds
  // the discs in cell order. A resumed run builds its lists again at the restart (other
  // candidates, the same history): the rule reads only the history and the positions.
  const SceneSpec spec = shuffled(janssen(2));
  World one;
  build_world(spec, one);
  for (long s = 0; s < 2500; ++s) one.step();
  ASSERT_EQ(one.resorts, 1);
  const std::string path = ::testing::TempDir() + "/disc_order.state";
  for (long split : {300L, 1900L}) {
    World a;
    build_world(spec, a);
    for (long s = 0; s < split; ++s) a.step();
    EXPECT_EQ(a.resorts, split < 1000 ? 0 : 1) << "split " << split;
    save_state(a, path);
    World b;
    build_world(spec, b);
    load_state(b, path);
    for (long s = split; s < 2500; ++s) b.step();
    EXPECT_EQ(b.resorts, split < 1000 ? 1 : 0) << "split " << split;
    ASSERT_EQ(b.discs.size(), one.discs.size());
    for (std::size_t i = 0; i < b.discs.size(); ++i) {
      ASSERT_EQ(b.discs.id_at(i), one.discs.id_at(i)) << "split " << split;
      ASSERT_EQ(b.discs.x[i], one.discs.x[i]) << "split " << split << " disc " << i;
      ASSERT_EQ(b.discs.y[i], one.discs.y[i]);
      ASSERT_EQ(b.discs.omega[i], one.discs.omega[i]);
    }
  }
  std::remove(path.c_str());
}

TEST(DiscOrder, RemovalsAfterAResortKeepIdsAndHistory) {
  // Removing discs from re-sorted arrays (an outlet) keeps every other disc's id and state: the
  // same as removing the same ids from the run in the user's order, to round-off.
  SceneSpec off = shuffled(janssen()), on = off;
  off.disc_order = DiscOrder::off;
  World a, b;
  build_world(off, a);
  build_world(on, b);
  step_both(a, b, 1800);
  ASSERT_EQ(b.resorts, 1);
  const auto remove_ids_below = [](World& w, int limit) {  // every disc of id < limit
    RemovedDiscs r;
    for (std::size_t i = 0; i < w.discs.size(); ++i)
      if (w.discs.id_at(i) < limit) r.sorted.push_back(static_cast<int>(i));
    w.remove_discs(r);
  };
  remove_ids_below(a, 1000);
  remove_ids_below(b, 1000);
  step_both(a, b, 600);
  ASSERT_EQ(a.discs.size(), 3500u);
  ASSERT_EQ(b.discs.size(), 3500u);
  std::vector<std::size_t> ia(4500, 0), ib(4500, 0);
  for (std::size_t i = 0; i < a.discs.size(); ++i) ia[a.discs.id_at(i)] = i;
  for (std::size_t i = 0; i < b.discs.size(); ++i) ib[b.discs.id_at(i)] = i;
  double worst = 0;
  for (int id = 1000; id < 4500; ++id) worst = std::max(worst, std::abs(a.discs.y[ia[id]] - b.discs.y[ib[id]]));
  EXPECT_LT(worst, 1e-9);
}

TEST(DiscOrder, DiscFileListsTheUserOrder) {
  SceneSpec spec = shuffled(janssen());
  World w;
  build_world(spec, w);
  for (long s = 0; s < 1800; ++s) w.step();
  ASSERT_EQ(w.resorts, 1);
  const std::string dir = ::testing::TempDir();
  write_disc_files(dir, "disc_order", spec, w.discs, nullptr);
  std::ifstream in(dir + "/disc_order.csv");
  std::string line;
  std::getline(in, line);
  const std::vector<std::size_t> at = user_order(w.discs);
  int k = 0;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string id, x;
    std::getline(row, id, ',');
    std::getline(row, x, ',');
    ASSERT_EQ(std::stoi(id), k) << "row " << k;
    ASSERT_EQ(std::stod(x), w.discs.x[at[k]]) << "row " << k;
    ++k;
  }
  EXPECT_EQ(k, 4500);
  std::remove((dir + "/disc_order.csv").c_str());
  std::remove((dir + "/disc_order.vtu").c_str());
}

TEST(DiscOrder, OffKeepsTheGivenOrder) {
  SceneSpec spec = shuffled(janssen());
  spec.disc_order = DiscOrder::off;
  World w;
  build_world(spec, w);
  for (long s = 0; s < 1800; ++s) w.step();
  EXPECT_EQ(w.resorts, 0);
  EXPECT_TRUE(w.discs.id.empty()) << "ids are the indices";
}
