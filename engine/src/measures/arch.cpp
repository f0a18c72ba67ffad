#include "measures/arch.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>
#include <utility>

#include "physics/world.hpp"

namespace dem {

namespace {

using Feet = std::vector<std::pair<int, char>>;  // (disc, bits): sorted by disc, one entry a disc
constexpr char kLeftFoot = 1, kRightFoot = 2;

enum class ArchSearch { found, none, too_far };

// One breadth-first search for the arch over the compressive pairs `above` (their (i, j), sorted).
// A disc's partners, in the order of the pairs: first those below it (their pairs come first), by
// increasing index, from `below` (the (j, i) of each pair, sorted); then those above it, from its
// own run of pairs. `reach2`: the pairs hold every partner of the discs within sqrt(reach2) of
// (ax, ay) only; popping a disc farther out gives too_far (the search may differ from one over
// all pairs from there).
using Pairs = std::vector<std::pair<int, int>>;
ArchSearch arch_bfs(const Discs& d, const Pairs& above, const Feet& feet, double floor_y, double ax, double ay,
                    double reach2, std::vector<int>& path) {
  const auto foot = [&](int i) -> char {
    const auto it = std::lower_bound(feet.begin(), feet.end(), std::make_pair(i, char(0)));
    return it != feet.end() && it->first == i ? it->second : 0;
  };
  const std::size_t nrec = above.size();
  Pairs below;
  below.reserve(nrec);
  for (const auto& a : above) below.emplace_back(a.second, a.first);
  std::sort(below.begin(), below.end());
  // The discs the search can reach or start from (those of the compressive pairs, and the
  // feet), sorted: a disc's place here indexes its predecessor on the search.
  std::vector<int> ids;
  {
    std::size_t a = 0, b = 0, f = 0;
    const auto next_rec = [&] {  // the i of the next pair, or INT_MAX
      return a < nrec ? above[a].first : std::numeric_limits<int>::max();
    };
    for (;;) {
      const int r = next_rec();
      const int q = b < below.size() ? below[b].first : std::numeric_limits<int>::max();
      const int t = f < feet.size() ? feet[f].first : std::numeric_limits<int>::max();
      const int k = std::min(r, std::min(q, t));
      if (k == std::numeric_limits<int>::max()) break;
      if (ids.empty() || ids.back() != k) ids.push_back(k);
      if (k == r) ++a;
      else if (k == q) ++b;
      else ++f;
    }
  }
  const auto place = [&](int i) { return std::lower_bound(ids.begin(), ids.end(), i) - ids.begin(); };
  std::vector<int> prev(ids.size(), -2);
  std::deque<int> q;
  for (const auto& f : feet)
    if (f.second & kLeftFoot) {
      prev[place(f.first)] = -1;
      q.push_back(f.first);
    }
  const auto visit = [&](int i, int j) {
    if (int& p = prev[place(j)]; p == -2 && d.y[j] > floor_y) {
      p = i;
      q.push_back(j);
    }
  };
  while (!q.empty()) {
    const int i = q.front();
    q.pop_front();
    if (foot(i) & kRightFoot) {
      path.clear();
      for (int k = i; k >= 0; k = prev[place(k)]) path.push_back(k);
      if (path.size() < 2) path.clear();  // one disc on both ends is not an arch
      return path.empty() ? ArchSearch::none : ArchSearch::found;
    }
    if (reach2 < std::numeric_limits<double>::infinity()) {  // all records (infinite reach): no test
      const double ex = d.x[i] - ax, ey = d.y[i] - ay;
      if (!(ex * ex + ey * ey <= reach2)) return ArchSearch::too_far;  // its partners may be missing
    }
    const auto lo = std::lower_bound(below.begin(), below.end(), std::make_pair(i, std::numeric_limits<int>::min()));
    for (auto it = lo; it != below.end() && it->first == i; ++it) visit(i, it->second);
    const auto first = std::lower_bound(above.begin(), above.end(), std::make_pair(i, std::numeric_limits<int>::min()));
    for (auto it = first; it != above.end() && it->first == i; ++it) visit(i, it->second);
  }
  return ArchSearch::none;
}

}  // namespace

std::vector<int> find_arch(const World& w, double slit_left, double slit_right, double floor_y, ArchStats* stats) {
  const Discs& d = w.discs;
  if (stats) *stats = ArchStats{};
  if (d.size() == 0) return {};
  double rmax = 0;
  for (std::size_t i = 0; i < d.size(); ++i) rmax = std::max(rmax, d.r(i));
  // Nothing here is sized by the number of discs: a loose packing (a silo started from its
  // lattice) has few contacts, and arrays of all discs (9 bytes a disc) set the peak of such a
  // run at 1M discs. Everything below is sized by the compressive pairs near the slit and the feet.
  // Feet: discs touching a slit end, as a point or as the bottom wall within 2 r of it; bit 1 a
  // left foot, bit 2 a right foot. A short list, sorted by disc.
  Feet feet;
  const int nw = static_cast<int>(w.geometry.walls.size());
  for (const WallContact& c : w.neighbors.walls) {
    if (!c.touching) continue;
    const bool near_floor = std::abs(c.py - floor_y) < 1e-9 * (1 + std::abs(floor_y));
    if (c.k >= nw || near_floor) {
      const char bits = static_cast<char>((std::abs(c.px - slit_left) <= 2 * rmax ? kLeftFoot : 0) |
                                          (std::abs(c.px - slit_right) <= 2 * rmax ? kRightFoot : 0));
      if (bits) feet.emplace_back(c.i, bits);
    }
  }
  std::sort(feet.begin(), feet.end());
  std::size_t nf = 0;
  for (const auto& f : feet) {  // one entry a disc, its bits or-ed
    if (nf > 0 && feet[nf - 1].first == f.first) feet[nf - 1].second |= f.second;
    else feet[nf++] = f;
  }
  feet.resize(nf);
  if (!w.pair_forces_current()) throw std::logic_error("find_arch: the pair forces of this step were not recorded");
  // The search in a disc of radius rho around the slit's centre first, over the compressive
  // records whose disc i lies in it (a copy sized by the slit's neighbourhood, not by the silo):
  // the whole packing's records sorted cost a serial sort of every compressive pair at each
  // sample. A partner is at most `hop` (the longest compressive pair) from its disc, so every
  // partner of a disc within rho - hop of the centre is among those records (its own pairs
  // through i, the others through their partner's i, within rho). A search that pops only such
  // discs runs exactly as over all records: the same chain. One that pops a disc farther out is
  // given up and run again in twice the radius, at last over all records.
  const double ax = 0.5 * (slit_left + slit_right), ay = floor_y;
  const auto dist2 = [&](int i) {
    const double ex = d.x[i] - ax, ey = d.y[i] - ay;
    return ex * ex + ey * ey;
  };
  double far2 = 0, hop2 = 0;  // the farthest compressive disc i, the longest compressive pair
  w.each_recorded_pair([&](int i, int j, double fn, double) {
    if (!(fn > 0)) return;
    far2 = std::max(far2, dist2(i));
    const double ex = d.x[j] - d.x[i], ey = d.y[j] - d.y[i];
    hop2 = std::max(hop2, ex * ex + ey * ey);
  });
  const double hop = std::sqrt(hop2);
  double feet_far = 0;
  for (const auto& f : feet) feet_far = std::max(feet_far, std::sqrt(dist2(f.first)));
  std::vector<int> path;
  Pairs near;  // the compressive pairs searched: (i, j), 8 bytes each
  for (double rho = feet_far + 8 * hop + rmax;; rho *= 2) {
    if (stats) ++stats->searches;
    near.clear();
    if (!(rho > 0) || !(rho * rho < far2)) {  // every record: the search as over the whole packing
      if (stats) stats->records += w.pair_totals.size();
      w.each_recorded_pair([&](int i, int j, double fn, double) {
        if (fn > 0) near.emplace_back(i, j);
      });
      arch_bfs(d, near, feet, floor_y, ax, ay, std::numeric_limits<double>::infinity(), path);
      return path;
    }
    w.each_recorded_pair([&](int i, int j, double fn, double) {
      if (fn > 0 && !(dist2(i) > rho * rho)) near.emplace_back(i, j);  // NaN: kept
    });
    if (stats) stats->records += near.size();
    // Margins of 1e-9: rounding in the distances never admits a disc whose partner is outside.
    const double reach = rho * (1 - 1e-9) - hop * (1 + 1e-9);
    const ArchSearch r = arch_bfs(d, near, feet, floor_y, ax, ay, reach > 0 ? reach * reach : -1.0, path);
    if (r != ArchSearch::too_far) return path;
  }
}

}  // namespace dem
