// The arch over the slit (measures/arch.cpp find_arch): the shortest chain of compressive contacts
// from a left foot to a right foot, found by a breadth-first search whose order is fixed (feet by
// increasing index, each disc's partners in the order of the recorded pair list). find_arch keeps
// no array the size of the discs; here the same search is written plainly, with an adjacency
// list per disc, and both must give the same chain on random contact graphs: with and without
// an arch, discs below the floor (never entered), tensile pairs (never followed), and a disc
// that is both feet (no arch).
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <random>
#include <vector>

#include "measures/arch.hpp"
#include "helpers.hpp"

using namespace dem;

namespace {

constexpr double kLeftX = 10.0, kRightX = 14.0, kFloor = 0.0;

// The plain search: every disc's partners appended in record order, feet by increasing index.
std::vector<int> plain_arch(const World& w) {
  const int n = static_cast<int>(w.discs.size());
  std::vector<char> foot(n, 0);
  double rmax = 0;
  for (int i = 0; i < n; ++i) rmax = std::max(rmax, w.discs.r(i));
  for (const WallContact& c : w.neighbors.walls) {
    if (!c.touching) continue;
    if (std::abs(c.px - kLeftX) <= 2 * rmax) foot[c.i] |= 1;
    if (std::abs(c.px - kRightX) <= 2 * rmax) foot[c.i] |= 2;
  }
  std::vector<std::vector<int>> adj(n);
  for (const PairForce& p : w.recorded_pairs())
    if (p.fn > 0) {
      adj[p.i].push_back(p.j);
      adj[p.j].push_back(p.i);
    }
  std::vector<int> prev(n, -2);
  std::deque<int> q;
  for (int i = 0; i < n; ++i)
    if (foot[i] & 1) {
      prev[i] = -1;
      q.push_back(i);
    }
  while (!q.empty()) {
    const int i = q.front();
    q.pop_front();
    if (foot[i] & 2) {
      std::vector<int> path;
      for (int k = i; k >= 0; k = prev[k]) path.push_back(k);
      return path.size() < 2 ? std::vector<int>{} : path;
    }
    for (int j : adj[i])
      if (prev[j] == -2 && w.discs.y[j] > kFloor) {
        prev[j] = i;
        q.push_back(j);
      }
  }
  return {};
}

}  // namespace

TEST(FindArch, SameChainAsThePlainSearchOnRandomContactGraphs) {
  std::mt19937 rng(2026);
  int arches = 0, none = 0;
  for (int trial = 0; trial < 300; ++trial) {
    PairProps p;
    p.kn = 1;
    World w = dem::testing::make_world(p, {}, Scheme::paper_eq19, 1e-4, -980.0);  // no walls: contacts are points
    const int n = 20 + static_cast<int>(rng() % 200);
    std::uniform_real_distribution<double> ux(0.0, 24.0), uy(-0.5, 20.0);
    for (int i = 0; i < n; ++i) w.discs.add(ux(rng), uy(rng), 0.5, 1.0, 0);
    // Random pairs (i < j), sorted by (i, j) as a recorded pass leaves them; some tensile.
    std::vector<PairForce> rec;
    const int m = static_cast<int>(rng() % (3 * n));
    for (int k = 0; k < m; ++k) {
      int i = static_cast<int>(rng() % n), j = static_cast<int>(rng() % n);
      if (i == j) continue;
      if (i > j) std::swap(i, j);
      rec.push_back(PairForce{i, j, (rng() % 5 == 0) ? -1.0 : 1.0 + (rng() % 7), 0.0});
    }
    std::sort(rec.begin(), rec.end(), [](const PairForce& a, const PairForce& b) { return a.i < b.i || (a.i == b.i && a.j < b.j); });
    rec.erase(std::unique(rec.begin(), rec.end(), [](const PairForce& a, const PairForce& b) { return a.i == b.i && a.j == b.j; }),
              rec.end());
    w.pair_totals.assign(rec);
    w.pair_forces_step = w.steps;
    // Feet: a few contacts at each slit end (some listed twice, some not touching), sometimes one
    // disc at both ends.
    std::vector<WallContact> walls;
    const auto add_foot = [&](int i, double px, bool touching) {
      WallContact c{};
      c.i = i; c.k = 0; c.px = px; c.py = kFloor; c.touching = touching;
      walls.push_back(c);
    };
    const int nl = 1 + static_cast<int>(rng() % 3), nr = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < nl; ++k) add_foot(static_cast<int>(rng() % n), kLeftX + 0.3, rng() % 6 != 0);
    for (int k = 0; k < nr; ++k) add_foot(static_cast<int>(rng() % n), kRightX - 0.3, rng() % 6 != 0);
    if (trial % 17 == 0) add_foot(walls.back().i, kLeftX, true);  // a disc on both ends
    std::sort(walls.begin(), walls.end(), [](const WallContact& a, const WallContact& b) { return a.i < b.i; });
    w.neighbors.walls = walls;
    const std::vector<int> want = plain_arch(w);
    const std::vector<int> got = find_arch(w, kLeftX, kRightX, kFloor);
    ASSERT_EQ(got, want) << "trial " << trial;
    if (want.empty()) ++none;
    else ++arches;
  }
  // Both outcomes occur often, so the comparison covers both.
  EXPECT_GT(arches, 50);
  EXPECT_GT(none, 50);
}

// A packing as a run leaves it: discs on a jittered triangular lattice, pairs only between
// touching discs. find_arch searches near the slit first and widens only when the search leaves
// that neighbourhood; it must give the plain search's chain whether the arch is low over the slit,
// forced high by a cut in the compressive network (the first neighbourhood too small), or absent.
TEST(FindArch, LocalSearchGivesThePlainChainOnPackings) {
  std::mt19937 rng(1983);
  int local = 0, widened = 0, whole = 0, arches = 0;
  for (int trial = 0; trial < 40; ++trial) {
    PairProps p;
    p.kn = 1;
    World w = dem::testing::make_world(p, {}, Scheme::paper_eq19, 1e-4, -980.0);
    const int cols = 70, rows = 45;
    const double r = 0.5, s = 0.98;  // spacing under 2 r: neighbours overlap
    std::uniform_real_distribution<double> jit(-0.004, 0.004);
    for (int row = 0; row < rows; ++row)
      for (int c = 0; c < cols; ++c)
        w.discs.add(r + c * s + (row % 2) * 0.5 * s + jit(rng), r * 0.99 + row * s * std::sqrt(0.75) + jit(rng), r, 1.0, 0);
    const int n = static_cast<int>(w.discs.size());
    // A cut: no compressive pair crosses x = 12 below the height `cut` (0: no cut; past the top:
    // no arch at all).
    const double cut = trial % 4 == 0 ? 0.0 : trial % 4 == 1 ? 6.0 : trial % 4 == 2 ? 30.0 : 1e9;
    std::vector<PairForce> rec;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const double dx = w.discs.x[j] - w.discs.x[i], dy = w.discs.y[j] - w.discs.y[i];
        if (dx * dx + dy * dy >= 4 * r * r) continue;
        const bool crosses = (w.discs.x[i] - 12) * (w.discs.x[j] - 12) < 0 && w.discs.y[i] < cut;
        rec.push_back(PairForce{i, j, crosses || rng() % 6 == 0 ? -1.0 : 1.0 + (rng() % 7), 0.0});
      }
    w.pair_totals.assign(rec);
    w.pair_forces_step = w.steps;
    std::vector<WallContact> walls;  // the bottom row's floor contacts within reach of a slit end
    for (int i = 0; i < cols; ++i)
      if (std::abs(w.discs.x[i] - kLeftX) <= 2 * r || std::abs(w.discs.x[i] - kRightX) <= 2 * r) {
        WallContact c{};
        c.i = i; c.k = 0; c.px = w.discs.x[i]; c.py = kFloor; c.touching = true;
        walls.push_back(c);
      }
    w.neighbors.walls = walls;
    const std::vector<int> want = plain_arch(w);
    ArchStats st;
    const std::vector<int> got = find_arch(w, kLeftX, kRightX, kFloor, &st);
    ASSERT_EQ(got, want) << "trial " << trial << " cut " << cut;
    arches += !want.empty();
    if (st.searches == 1 && st.records < rec.size() / 4) ++local;
    else if (st.records < rec.size()) ++widened;
    else ++whole;
  }
  // Each way through the search occurs: settled near the slit, widened, over all records.
  EXPECT_GT(local, 5);
  EXPECT_GT(widened, 5);
  EXPECT_GT(whole, 5);
  EXPECT_GT(arches, 20);
}
