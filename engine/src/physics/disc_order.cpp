#include "physics/disc_order.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dem {

OrderGrid order_grid(const Discs& d, double skin, double min_cell) {
  const double inf = std::numeric_limits<double>::infinity();
  double rmax = 0, x0 = inf, x1 = -inf, y0 = inf, y1 = -inf;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (std::isfinite(d.r(i))) rmax = std::max(rmax, d.r(i));
    if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i])) continue;
    x0 = std::min(x0, d.x[i]); x1 = std::max(x1, d.x[i]);
    y0 = std::min(y0, d.y[i]); y1 = std::max(y1, d.y[i]);
  }
  if (!(x0 <= x1)) x0 = x1 = y0 = y1 = 0;
  long double cell = std::max(min_cell, 2 * rmax + skin);
  if (!std::isfinite(cell) || !(cell > 0)) cell = 1;
  const long double max_cells = 4.0L * static_cast<long double>(d.size()) + 64;
  const auto along = [&](long double extent) { return std::floor(extent / cell) + 1; };
  while (along(static_cast<long double>(x1) - x0) * along(static_cast<long double>(y1) - y0) > max_cells) cell *= 2;
  OrderGrid g;
  g.xmin = x0;
  g.ymin = y0;
  g.inv_cell = 1.0 / static_cast<double>(cell);
  g.nx = static_cast<long>(along(static_cast<long double>(x1) - x0));
  g.ny = static_cast<long>(along(static_cast<long double>(y1) - y0));
  return g;
}

long OrderGrid::cell_of(double x, double y) const {
  if (!std::isfinite(x) || !std::isfinite(y)) return nx * ny;
  const double fx = (x - xmin) * inv_cell, fy = (y - ymin) * inv_cell;
  const long cx = fx < static_cast<double>(nx - 1) ? static_cast<long>(fx) : nx - 1;
  const long cy = fy < static_cast<double>(ny - 1) ? static_cast<long>(fy) : ny - 1;
  return cy * nx + cx;
}

std::vector<int> cell_order(const Discs& d, const OrderGrid& g) {
  const int n = static_cast<int>(d.size());
  const long slots = g.nx * g.ny + 1;  // the last: no cell
  std::vector<int> start(slots + 1, 0);
  for (int i = 0; i < n; ++i) ++start[g.cell_of(d.x[i], d.y[i]) + 1];
  for (long c = 0; c < slots; ++c) start[c + 1] += start[c];
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[start[g.cell_of(d.x[i], d.y[i])]++] = i;
  // start[c] is now the end of cell c. Within each cell (one or two discs, a few at most) by x:
  // an insertion sort, stable, so equal x keep the order of their indices.
  for (long c = 0, begin = 0; c + 1 < slots; begin = start[c], ++c)
    for (long s = begin + 1; s < start[c]; ++s) {
      const int disc = order[s];
      long t = s;
      for (; t > begin && d.x[order[t - 1]] > d.x[disc]; --t) order[t] = order[t - 1];
      order[t] = disc;
    }
  return order;
}

double disc_order_spread(const std::vector<PairContact>& pairs, const Discs& d, long rows) {
  const std::size_t n = d.size();
  if (n == 0 || rows <= 0) return 0;
  // Integer sums: exact, the same in any order.
  long long gap = 0, count = 0;
  for (const PairContact& p : pairs) {
    const double dx = d.x[p.j] - d.x[p.i], dy = d.y[p.j] - d.y[p.i], sum = d.r(p.i) + d.r(p.j);
    if (dx * dx + dy * dy <= sum * sum) {  // (3): overlapping
      gap += p.j > p.i ? p.j - p.i : p.i - p.j;
      ++count;
    }
  }
  if (count == 0) return 0;
  const double mean = static_cast<double>(gap) / static_cast<double>(count);
  return mean * static_cast<double>(rows) / static_cast<double>(n);
}

bool disc_order_degraded(const std::vector<PairContact>& pairs, const Discs& d, long rows) {
  return d.size() >= DiscOrderRule::kMinDiscs && disc_order_spread(pairs, d, rows) > DiscOrderRule::kMaxSpread;
}

const char* to_string(DiscOrder o) { return o == DiscOrder::off ? "off" : "auto"; }

}  // namespace dem
