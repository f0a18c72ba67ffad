#include "neighbors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.hpp"

namespace dem {

bool Neighbors::needs_rebuild(const Discs& d, int nt) const {
  if (x0_.size() != d.size()) return true;
  const double lim2 = 0.25 * skin * skin;
  const long n = static_cast<long>(d.size());
  if (nt <= 1) {
    for (long i = 0; i < n; ++i) {
      const double dx = d.x[i] - x0_[i], dy = d.y[i] - y0_[i];
      if (dx * dx + dy * dy > lim2) return true;
    }
    return false;
  }
  bool far = false;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(|| : far)
  for (long i = 0; i < n; ++i) {
    const double dx = d.x[i] - x0_[i], dy = d.y[i] - y0_[i];
    far = far || dx * dx + dy * dy > lim2;
  }
  return far;
}

namespace {
// Keep the history of entries present in both sorted lists (same key).
template <class T, class Key>
void merge_history(const std::vector<T>& old_list, std::vector<T>& new_list, Key key) {
  if (new_list.empty()) return;
  // A block's new entries start somewhere in the old list: skip there at once.
  std::size_t a = std::lower_bound(old_list.begin(), old_list.end(), key(new_list.front()),
                                   [&](const T& o, long long k) { return key(o) < k; }) - old_list.begin();
  for (auto& e : new_list) {
    while (a < old_list.size() && key(old_list[a]) < key(e)) ++a;
    if (a < old_list.size() && key(old_list[a]) == key(e)) e = old_list[a];
  }
}

}  // namespace

void Neighbors::rebuild(const Discs& d, const Geometry& g, int nt) {
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

  grid_ = Grid{static_cast<double>(xmin), static_cast<double>(ymin), nx, ny};
  const auto pair_key = [](const PairContact& p) { return (static_cast<long long>(p.i) << 32) | static_cast<unsigned>(p.j); };
  const auto wall_key = [](const WallContact& w) { return (static_cast<long long>(w.i) << 32) | static_cast<unsigned>(w.k); };
  if (nt <= 1) {
    new_pairs_.clear();
    new_walls_.clear();
    search(d, g, 0, n, new_pairs_, new_walls_);
    merge_history(pairs, new_pairs_, pair_key);
    merge_history(walls, new_walls_, wall_key);
    pairs.swap(new_pairs_);
    walls.swap(new_walls_);
    return;
  }
  // Threads search contiguous blocks of discs; the lists are sorted by i, so the blocks'
  // lists, each merged with the old entries of its discs, concatenate in order: the same lists as
  // the serial search, whatever the thread count.
  block_pairs_.resize(nt);
  block_walls_.resize(nt);
  std::vector<std::size_t> pair_at(nt + 1, 0), wall_at(nt + 1, 0);
#pragma omp parallel num_threads(nt)
  {
    const int t = omp_thread_index();
    const int i0 = block_start(n, nt, t), i1 = block_start(n, nt, t + 1);
    auto& bp = block_pairs_[t];
    auto& bw = block_walls_[t];
    bp.clear();
    bw.clear();
    search(d, g, i0, i1, bp, bw);
    merge_history(pairs, bp, pair_key);
    merge_history(walls, bw, wall_key);
    pair_at[t + 1] = bp.size();
    wall_at[t + 1] = bw.size();
#pragma omp barrier
#pragma omp single
    {
      for (int u = 0; u < nt; ++u) {
        pair_at[u + 1] += pair_at[u];
        wall_at[u + 1] += wall_at[u];
      }
      pairs.resize(pair_at[nt]);
      walls.resize(wall_at[nt]);
    }
    std::copy(bp.begin(), bp.end(), pairs.begin() + static_cast<std::ptrdiff_t>(pair_at[t]));
    std::copy(bw.begin(), bw.end(), walls.begin() + static_cast<std::ptrdiff_t>(wall_at[t]));
  }
}

void Neighbors::search(const Discs& d, const Geometry& g, int i0, int i1, std::vector<PairContact>& out_pairs,
                       std::vector<WallContact>& out_walls) const {
  const long nx = grid_.nx, ny = grid_.ny;
  std::vector<int> found;
  for (int i = i0; i < i1; ++i) {
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
    for (int j : found) out_pairs.push_back(PairContact{i, j});
  }
  const int nk = g.obstacle_count();
  for (int i = i0; i < i1; ++i)
    for (int k = 0; k < nk; ++k)
      if (obstacle_distance(g, k, d.x[i], d.y[i]) < d.r[i] + skin) out_walls.push_back(WallContact{i, k});
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
