// The pair list is rebuilt in place, over the old one (neighbors.cpp build_pairs): whatever
// the old list, the new one must be exactly the fresh list of the new positions, with the
// history of the pairs the two lists share, for 1 and 2 threads, when the list grows past its
// margin (the buffer is enlarged mid-build), when it grows within it (the unread old entries are
// moved to the buffer's tail mid-build) and when it shrinks; and the scratch kept between builds
// must not grow with the number of discs.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "physics/neighbors.hpp"

namespace dem {
namespace {

// A square lattice of discs of radius 1, spacing `gap` (centre to centre), rows of `row`.
Discs lattice(int n, int row, double gap) {
  Discs d;
  for (int k = 0; k < n; ++k) d.add((k % row) * gap, (k / row) * gap, 1.0, 1.0, 0);
  return d;
}

// Distinct, recognisable history for every pair of a list.
double tag(const PairContact& c) { return c.i * 1e5 + c.j; }

// Returns whether the build kept the list's buffer (no enlargement).
bool check_rebuild(const Discs& before, const Discs& after, int threads) {
  const Geometry g;
  Neighbors nb;
  nb.rebuild(before, g, threads);
  for (PairContact& c : nb.pairs) {
    c.en = tag(c);
    c.es = -tag(c);
  }
  std::vector<PairContact> old = nb.pairs;
  const PairContact* buffer = nb.pairs.data();
  nb.rebuild(after, g, threads);
  const bool kept_buffer = nb.pairs.data() == buffer;

  Neighbors fresh;
  fresh.rebuild(after, g, 1);
  EXPECT_EQ(nb.pairs.size(), fresh.pairs.size()) << threads << " threads";
  if (nb.pairs.size() != fresh.pairs.size()) return kept_buffer;
  std::size_t a = 0, kept = 0;
  for (std::size_t p = 0; p < fresh.pairs.size(); ++p) {
    const PairContact& c = nb.pairs[p];
    EXPECT_EQ(c.i, fresh.pairs[p].i) << p;
    EXPECT_EQ(c.j, fresh.pairs[p].j) << p;
    if (c.i != fresh.pairs[p].i || c.j != fresh.pairs[p].j) return kept_buffer;
    while (a < old.size() && (old[a].i < c.i || (old[a].i == c.i && old[a].j < c.j))) ++a;
    const bool shared = a < old.size() && old[a].i == c.i && old[a].j == c.j;
    EXPECT_EQ(c.en, shared ? tag(c) : 0.0) << c.i << "-" << c.j;
    EXPECT_EQ(c.es, shared ? -tag(c) : 0.0) << c.i << "-" << c.j;
    kept += shared;
  }
  EXPECT_GT(kept, 0u) << "no shared pair: the history part of the test cannot fail";
  return kept_buffer;
}

TEST(Neighbors, InPlaceBuildGrowingPastItsMarginIsTheFreshList) {
  // 20000 discs 3 apart (no candidates), then the first 12000 packed at spacing 2 (about 2 pairs
  // a disc): the list grows from nothing to ~24k pairs within the first rounds, far past the
  // 1/16 margin, so the buffer is enlarged in the middle of the build.
  const int n = 20000, row = 100;
  Discs before = lattice(n, row, 2.1);  // 2.1 apart with skin 0.2: every lattice neighbour a candidate
  for (int k = 0; k < 8000; ++k) before.x[k] += 3 * row;  // the first 8000 spread out: fewer pairs
  for (int k = 0; k < 8000; ++k) before.x[k] = (k % row) * 3.0, before.y[k] = (k / row) * 3.0 + 1000;
  Discs after = lattice(n, row, 2.1);
  for (int threads : {1, 2}) EXPECT_FALSE(check_rebuild(before, after, threads)) << "the buffer was not enlarged";
}

TEST(Neighbors, InPlaceBuildGrowingWithinItsMarginIsTheFreshList) {
  // 20000 discs 2.1 apart (about 2 pairs a disc), of which the first 300 start spread out (no
  // pairs): the first round's new entries need more room than the old entries of its discs
  // leave in front of the next round's, so the unread old entries are moved to the tail of the
  // buffer mid-build; the whole list grows by some 2 %, within the 1/16 margin, so the buffer
  // is kept.
  const int n = 20000, row = 100;
  Discs before = lattice(n, row, 2.1);
  for (int k = 0; k < 300; ++k) before.x[k] = (k % row) * 3.0, before.y[k] = (k / row) * 3.0 + 1000;
  Discs after = lattice(n, row, 2.1);
  for (int threads : {1, 2}) EXPECT_TRUE(check_rebuild(before, after, threads)) << "the buffer was kept";
}

TEST(Neighbors, ObstacleCandidatesAreEveryDiscWithinReach) {
  // The obstacle entries come from the cells under each obstacle's box (search_walls): they must
  // be exactly the discs within r + skin of each live obstacle, found by testing every disc
  // against every obstacle, in (i, k) order. Walls along the packing's edges, across it on a
  // slant, reaching far past the discs (boxes beyond the grid), one removed, and points, over
  // discs of two radii.
  Discs d;
  unsigned s = 12345;
  const auto rnd = [&] { return (s = s * 1103515245u + 12345u) / 4294967296.0; };
  for (int k = 0; k < 3000; ++k) d.add(100 * rnd(), 60 * rnd(), k % 3 ? 0.5 : 0.8, 1.0, 0);
  Geometry g;
  g.walls.push_back({"floor", "b", -50, 0, 150, 0, 0});
  g.walls.push_back({"left", "s", 0, 500, 0, -500, 0});
  g.walls.push_back({"slant", "s", 10, 5, 90, 55, 0});
  g.walls.push_back({"gone", "s", 0, 30, 100, 30, 0, false});
  g.walls.push_back({"short", "s", 40, 20, 41, 21, 0});
  g.points.push_back({"p", "p", 50, 30, 0, {}});
  g.points.push_back({"q", "p", 99.9, 59.9, 0, {}});
  g.points.push_back({"far", "p", -400, 900, 0, {}});
  for (int threads : {1, 2}) {
    Neighbors nb;
    nb.rebuild(d, g, threads);
    std::vector<std::pair<int, int>> want, got;
    for (int i = 0; i < static_cast<int>(d.size()); ++i)
      for (int k = 0; k < g.obstacle_count(); ++k)
        if (obstacle_distance(g, k, d.x[i], d.y[i]) < d.r(i) + nb.skin) want.emplace_back(i, k);
    for (const WallContact& c : nb.walls) got.emplace_back(c.i, c.k);
    EXPECT_GT(want.size(), 100u) << "the test needs discs near the obstacles";
    EXPECT_EQ(got, want) << threads << " threads";
  }
}

TEST(Neighbors, InPlaceBuildShrinkingIsTheFreshList) {
  const int n = 20000, row = 100;
  Discs before = lattice(n, row, 2.1);
  Discs after = before;
  for (int k = 5000; k < 15000; ++k) after.y[k] += 0.05 * ((k * 7919) % 13);  // some pairs end
  for (int k = 15000; k < n; ++k) after.x[k] = 1000 + (k % row) * 3.0;     // the last ones part
  for (int threads : {1, 2}) check_rebuild(before, after, threads);
}

TEST(Neighbors, ScratchDoesNotGrowWithTheDiscs) {
  // The old build kept a second list the size of the first as scratch; the in-place build keeps
  // one round's worth a thread. From 20k to 80k discs the list grows 4x, the scratch not at all.
  const Geometry g;
  std::size_t scratch[2] = {0, 0}, list[2] = {0, 0};
  int s = 0;
  for (int n : {20000, 80000}) {
    Discs d = lattice(n, 200, 2.1);
    Neighbors nb;
    nb.rebuild(d, g, 2);
    nb.rebuild(d, g, 2);
    scratch[s] = nb.scratch_bytes();
    list[s] = nb.pairs.capacity() * sizeof(PairContact);
    ++s;
  }
  EXPECT_GT(list[1], 3 * list[0]);
  EXPECT_LE(scratch[1], scratch[0] + scratch[0] / 8) << "scratch grows with the discs";
  EXPECT_LT(scratch[1], list[1] / 4);
}

// The reference positions are floats relative to the grid's corner (8 bytes a disc less): the
// limit must still catch every disc that has truly moved more than skin/2 from where it was at
// the build. The worst case for each disc: moved straight along its own rounding error, which
// shortens the displacement the test computes by the whole error. Discs far from the origin (a
// silo 3000 cm tall, offset by 1e4 cm) make the errors as large as this scene allows.
TEST(Neighbors, FloatReferencesCatchEveryDiscPastHalfTheSkin) {
  Discs d;
  const int n = 4000;
  unsigned s = 12345;
  const auto uniform = [&] { s = s * 1664525u + 1013904223u; return (s >> 8) / 16777216.0; };
  for (int k = 0; k < n; ++k) d.add(1e4 + 1264 * uniform(), -5e3 + 3000 * uniform(), 0.5, 1.0, 0);
  Neighbors nb;
  nb.skin = 0.2;
  nb.rebuild(d, Geometry{}, 1);
  const double lim = std::sqrt(nb.moved_far_limit2());
  EXPECT_GT(lim, 0.5 * nb.skin * (1 - 1e-2)) << "the allowance for rounding is under 1 % of skin/2 here";
  EXPECT_LE(lim, 0.5 * nb.skin);
  int worst_cases = 0;
  for (int i = 0; i < n; ++i) {
    const double ex = (nb.origin_x() + nb.reference_x()[i]) - d.x[i];  // the float's error
    const double ey = (nb.origin_y() + nb.reference_y()[i]) - d.y[i];
    const double e = std::hypot(ex, ey);
    if (e == 0) continue;
    worst_cases += e > 1e-5;
    const double step = 0.5 * nb.skin * (1 + 1e-9);  // just past skin/2, along the error
    const double x = d.x[i] + step * ex / e, y = d.y[i] + step * ey / e;
    ASSERT_GT(std::hypot(x - d.x[i], y - d.y[i]), 0.5 * nb.skin) << "the move itself is past skin/2";
    const double dx = (x - nb.origin_x()) - nb.reference_x()[i], dy = (y - nb.origin_y()) - nb.reference_y()[i];
    EXPECT_GT(dx * dx + dy * dy, nb.moved_far_limit2()) << "disc " << i << " moved skin/2 and is not caught";
    // And half the skin less the allowance is not far: the test is not simply always true.
    const double near = 0.5 * (lim - 2 * e);
    const double xn = d.x[i] + near * ex / e, yn = d.y[i] + near * ey / e;
    const double ndx = (xn - nb.origin_x()) - nb.reference_x()[i], ndy = (yn - nb.origin_y()) - nb.reference_y()[i];
    EXPECT_LE(ndx * ndx + ndy * ndy, nb.moved_far_limit2()) << i;
  }
  EXPECT_GT(worst_cases, n / 2) << "most references carry a rounding error (floats of numbers near 1e3)";
}

}  // namespace
}  // namespace dem

namespace dem {
TEST(Neighbors, ThreadsSortTheCellsOfDiscsInAnyOrder) {
  // The threaded cell sort lets each thread place the discs of its block that lie in its rows
  // and places the others ("strays") after: discs in height order (few strays), upside down and
  // shuffled (most of them strays) must give the lists of one thread.
  Discs rows = lattice(3000, 50, 2.05);
  for (int order = 0; order < 3; ++order) {
    Discs d;
    std::vector<int> idx(rows.size());
    for (std::size_t k = 0; k < idx.size(); ++k) idx[k] = static_cast<int>(k);
    if (order == 1) std::reverse(idx.begin(), idx.end());
    if (order == 2) {
      unsigned s = 777;
      for (std::size_t k = idx.size(); k > 1; --k) std::swap(idx[k - 1], idx[(s = s * 1103515245u + 12345u) % k]);
    }
    for (int k : idx) d.add(rows.x[k], rows.y[k], 1.0, 1.0, 0);
    Geometry g;
    g.walls.push_back({"floor", "b", -5, -1.1, 120, -1.1, 0});
    Neighbors one, two, three;
    one.rebuild(d, g, 1);
    two.rebuild(d, g, 2);
    three.rebuild(d, g, 3);
    ASSERT_GT(one.pairs.size(), 5000u);
    ASSERT_GT(one.walls.size(), 40u);
    for (const Neighbors* nb : {&two, &three}) {
      ASSERT_EQ(nb->pairs.size(), one.pairs.size()) << "order " << order;
      for (std::size_t p = 0; p < one.pairs.size(); ++p) {
        ASSERT_EQ(nb->pairs[p].i, one.pairs[p].i) << "order " << order << " pair " << p;
        ASSERT_EQ(nb->pairs[p].j, one.pairs[p].j) << "order " << order << " pair " << p;
      }
      ASSERT_EQ(nb->walls.size(), one.walls.size()) << "order " << order;
      for (std::size_t k = 0; k < one.walls.size(); ++k) ASSERT_EQ(nb->walls[k].i, one.walls[k].i);
    }
  }
}
}  // namespace dem
