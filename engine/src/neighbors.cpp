#include "neighbors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dem {

bool Neighbors::needs_rebuild(const Discs& d) const {
  if (x0_.size() != d.size()) return true;
  const double lim2 = 0.25 * skin * skin;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double dx = d.x[i] - x0_[i], dy = d.y[i] - y0_[i];
    if (dx * dx + dy * dy > lim2) return true;
  }
  return false;
}

namespace {
// Keep the history of entries present in both sorted lists (same key).
template <class T, class Key>
void merge_history(const std::vector<T>& old_list, std::vector<T>& new_list, Key key) {
  std::size_t a = 0;
  for (auto& e : new_list) {
    while (a < old_list.size() && key(old_list[a]) < key(e)) ++a;
    if (a < old_list.size() && key(old_list[a]) == key(e)) e = old_list[a];
  }
}

}  // namespace

void Neighbors::rebuild(const Discs& d, const Geometry& g) {
  const int n = static_cast<int>(d.size());
  ++rebuilds;
  x0_ = d.x;
  y0_ = d.y;

  // Cells: at least one diameter plus skin, so neighbours are in the 3 x 3 block. Extents and
  // cell indices in long double, where no difference of finite coordinates overflows; discs at
  // non-finite positions (a run blowing up, stopped after this step) are in no cell and get no
  // pairs. Sparse scenes (discs flung far apart, tiny discs in a huge box) would need huge grids:
  // the cells are coarsened until there are at most 4 n + 64 of them.
  double rmax = 0;
  long double xmin = 0, xmax = 0, ymin = 0, ymax = 0;
  bool any = false;
  for (int i = 0; i < n; ++i) {
    if (std::isfinite(d.r[i])) rmax = std::max(rmax, d.r[i]);
    if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i])) continue;
    const long double x = d.x[i], y = d.y[i];
    if (!any) {
      xmin = xmax = x;
      ymin = ymax = y;
      any = true;
    }
    xmin = std::min(xmin, x); xmax = std::max(xmax, x);
    ymin = std::min(ymin, y); ymax = std::max(ymax, y);
  }
  long double cell = std::max(min_cell, 2 * rmax + skin);
  if (!std::isfinite(cell)) cell = std::numeric_limits<long double>::max();  // one cell for all
  if (!(cell > 0)) cell = 1;  // zero radii and skin (or NaN): nothing can pair, any size will do
  const long double max_cells = 4.0L * n + 64;
  auto cells_along = [&](long double extent) { return std::floor(extent / cell) + 1; };
  while (cells_along(xmax - xmin) * cells_along(ymax - ymin) > max_cells) cell *= 2;
  cell_ = static_cast<double>(cell);
  const long nx = static_cast<long>(cells_along(xmax - xmin));
  const long ny = static_cast<long>(cells_along(ymax - ymin));
  const long ncell = nx * ny;
  cell_of_.resize(n);
  cell_start_.assign(ncell + 1, 0);
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(d.x[i]) || !std::isfinite(d.y[i])) {
      cell_of_[i] = -1;
      continue;
    }
    const long cx = std::min(nx - 1, static_cast<long>((d.x[i] - xmin) / cell));
    const long cy = std::min(ny - 1, static_cast<long>((d.y[i] - ymin) / cell));
    cell_of_[i] = static_cast<int>(cy * nx + cx);
    ++cell_start_[cell_of_[i] + 1];
  }
  for (long c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
  order_.resize(n);
  {
    std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (int i = 0; i < n; ++i)
      if (cell_of_[i] >= 0) order_[fill[cell_of_[i]]++] = i;
  }

  new_pairs_.clear();
  std::vector<int> found;
  for (int i = 0; i < n; ++i) {
    if (cell_of_[i] < 0) continue;
    const long ci = cell_of_[i] % nx, cj = cell_of_[i] / nx;
    found.clear();
    for (long b = std::max(0L, cj - 1); b <= std::min(ny - 1, cj + 1); ++b)
      for (long a = std::max(0L, ci - 1); a <= std::min(nx - 1, ci + 1); ++a) {
        const long c = b * nx + a;
        for (int s = cell_start_[c]; s < cell_start_[c + 1]; ++s) {
          const int j = order_[s];
          if (j <= i) continue;
          const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
          const double reach = d.r[i] + d.r[j] + skin;
          if (dx * dx + dy * dy < reach * reach) found.push_back(j);
        }
      }
    std::sort(found.begin(), found.end());
    for (int j : found) new_pairs_.push_back(PairContact{i, j});
  }
  merge_history(pairs, new_pairs_, [](const PairContact& p) {
    return (static_cast<long long>(p.i) << 32) | static_cast<unsigned>(p.j);
  });
  pairs.swap(new_pairs_);

  new_walls_.clear();
  const int nk = g.obstacle_count();
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < nk; ++k)
      if (obstacle_distance(g, k, d.x[i], d.y[i]) < d.r[i] + skin) new_walls_.push_back(WallContact{i, k});
  merge_history(walls, new_walls_, [](const WallContact& w) {
    return (static_cast<long long>(w.i) << 32) | static_cast<unsigned>(w.k);
  });
  walls.swap(new_walls_);
}

}  // namespace dem

namespace dem {

void Neighbors::compact(const std::vector<int>& new_index) {
  std::size_t o = 0;
  for (const PairContact& p : pairs) {
    const int i = new_index[p.i], j = new_index[p.j];
    if (i < 0 || j < 0) continue;
    PairContact q = p;
    q.i = i;
    q.j = j;
    pairs[o++] = q;
  }
  pairs.resize(o);
  o = 0;
  for (const WallContact& w : walls) {
    const int i = new_index[w.i];
    if (i < 0) continue;
    WallContact q = w;
    q.i = i;
    walls[o++] = q;
  }
  walls.resize(o);
  o = 0;
  for (std::size_t k = 0; k < new_index.size() && k < x0_.size(); ++k)
    if (new_index[k] >= 0) {
      x0_[o] = x0_[k];
      y0_[o] = y0_[k];
      ++o;
    }
  x0_.resize(o);
  y0_.resize(o);
}

}  // namespace dem
