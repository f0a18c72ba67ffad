#include "physics/neighbors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physics/parallel.hpp"

namespace dem {

namespace {
// Keep the history of entries present in both sorted lists (same key): the old entries are
// [old_begin, old_end).
template <class T, class Key>
void merge_history(const T* old_begin, const T* old_end, std::vector<T>& new_list, Key key) {
  if (new_list.empty()) return;
  // A block's new entries start somewhere in the old list: skip there at once.
  const T* a = std::lower_bound(old_begin, old_end, key(new_list.front()),
                                [&](const T& o, long long k) { return key(o) < k; });
  for (auto& e : new_list) {
    while (a < old_end && key(*a) < key(e)) ++a;
    if (a < old_end && key(*a) == key(e)) e = *a;
  }
}
template <class T, class Key>
void merge_history(const std::vector<T>& old_list, std::vector<T>& new_list, Key key) {
  merge_history(old_list.data(), old_list.data() + old_list.size(), new_list, key);
}

// Lists are sized from the last build plus a margin, never by doubling: a list costs about its
// length, not up to twice that (what counts at a million discs).
template <class T>
void make_room(std::vector<T>& v, std::size_t expected) {
  v.clear();
  if (expected > 0) v.reserve(expected + expected / 16 + 64);
}
template <class T>
void fit(std::vector<T>& v) {
  if (v.capacity() > v.size() + v.size() / 8 + 1024) v.shrink_to_fit();
}
template <class T>
void resize_exact(std::vector<T>& v, std::size_t n) {  // contents not kept
  if (n > v.capacity()) {
    v.clear();
    v.reserve(n + n / 16 + 64);
  }
  v.resize(n);
}

// Function objects, not functions: merge_history is instantiated for each and inlines the key
// (through a function pointer it is called twice a step of its merge: 5 % of a build).
constexpr auto pair_key = [](const PairContact& p) {
  return (static_cast<long long>(p.i) << 32) | static_cast<unsigned>(p.j);
};
constexpr auto wall_key = [](const WallContact& w) {
  return (static_cast<long long>(w.i) << 32) | static_cast<unsigned>(w.k);
};

}  // namespace

void Neighbors::rebuild(const Discs& d, const Geometry& g, int nt) {
  const int n = static_cast<int>(d.size());
  ++rebuilds;
  // Cells: at least one diameter plus skin, so neighbours are in the 3 x 3 block. Extents in long
  // double, where no difference of finite coordinates overflows (cell indices clamped); discs at
  // non-finite positions (a run blowing up, stopped after this step) are in no cell and get no
  // pairs. Sparse scenes (discs flung far apart, tiny discs in a huge box) would need huge grids:
  // the cells are coarsened until there are at most 4 n + 64 of them.
  // The extremes in double (exact, in any order: per thread, then combined), their differences
  // below in long double.
  const double inf = std::numeric_limits<double>::infinity();
  double rmax = 0, dxmin = inf, dxmax = -inf, dymin = inf, dymax = -inf;
  const auto extend = [&](int i, double& rm, double& x0, double& x1, double& y0, double& y1) {
    if (std::isfinite(d.r(i))) rm = std::max(rm, d.r(i));
    const double x = d.x[i], y = d.y[i];
    if (!std::isfinite(x) || !std::isfinite(y)) return;
    x0 = std::min(x0, x); x1 = std::max(x1, x);
    y0 = std::min(y0, y); y1 = std::max(y1, y);
  };
  if (nt <= 1) {
    // Locals of their own: the reduction below takes the others' addresses, which kept them in
    // memory, a store and a load a disc in a chain (a third of this function's time).
    double rm = 0, x0 = inf, x1 = -inf, y0 = inf, y1 = -inf;
    for (int i = 0; i < n; ++i) extend(i, rm, x0, x1, y0, y1);
    rmax = rm; dxmin = x0; dxmax = x1; dymin = y0; dymax = y1;
  } else {
#pragma omp parallel for schedule(static) num_threads(nt) reduction(max : rmax, dxmax, dymax) \
    reduction(min : dxmin, dymin)
    for (int i = 0; i < n; ++i) extend(i, rmax, dxmin, dxmax, dymin, dymax);
  }
  if (!(dxmin <= dxmax)) dxmin = dxmax = dymin = dymax = 0;  // no finite disc
  const long double xmin = dxmin, xmax = dxmax, ymin = dymin, ymax = dymax;
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
  grid_ = Grid{dxmin, dymin, 1.0 / cell_, nx, ny};
  // Reference positions relative to the grid's corner, as floats: each off by at most 2^-24 of
  // the extent (round to nearest), so a disc's displacement by at most sqrt(2) of that; the limit
  // is skin/2 less twice that (the double differences round too), at least 0: every step
  // rebuilds if the skin is below float precision at this extent.
  x0_.resize(n);
  y0_.resize(n);
  parallel_for(n, nt, [&](long i) {
    x0_[i] = static_cast<float>(d.x[i] - dxmin);
    y0_[i] = static_cast<float>(d.y[i] - dymin);
  });
  const double rounding = std::sqrt(2.0) * std::ldexp(std::max(dxmax - dxmin, dymax - dymin), -23);
  const double allowed = std::max(0.0, 0.5 * skin - rounding);
  limit2_ = allowed * allowed;
  rounding_ = 0.5 * skin - allowed;
  rmax_ = rmax;
  ref_boxes_.clear();
  sort_by_cell(d, ncell, nt);
  // Each obstacle's box grown by the largest reach: a disc outside it cannot be a candidate, so
  // most discs skip the distance to most walls (the same lists, far fewer square roots).
  const double reach = rmax + skin;
  const int nk = g.obstacle_count(), nw = static_cast<int>(g.walls.size());
  boxes_.resize(nk);
  for (int k = 0; k < nk; ++k) {
    Box& b = boxes_[k];
    if (k < nw) {
      const Wall& w = g.walls[k];
      b = Box{std::min(w.ax, w.bx) - reach, std::max(w.ax, w.bx) + reach,
              std::min(w.ay, w.by) - reach, std::max(w.ay, w.by) + reach, w.active};
    } else {
      const Point& q = g.points[k - nw];
      b = Box{q.x - reach, q.x + reach, q.y - reach, q.y + reach, true};
    }
    if (!std::isfinite(reach)) b = Box{-HUGE_VAL, HUGE_VAL, -HUGE_VAL, HUGE_VAL, b.live};
  }
  build_pairs(d, nt);
  // Obstacle entries: a few per disc at a wall, a small list, built beside the old one from the
  // discs of the cells under each obstacle's box.
  make_room(new_walls_, walls.size());
  search_walls(d, g, new_walls_);
  fit(new_walls_);
  merge_history(walls, new_walls_, wall_key);
  walls.swap(new_walls_);
  // The cells serve this build only: freed, not kept for the next (at a million discs 8 bytes a
  // disc or more, which would add to the peak of the steps between builds).
  std::vector<int>().swap(order_);
  std::vector<int>().swap(cell_start_);
}

// A counting sort by cell; each pass computes the discs' cells again (Grid::cell_of) rather
// than keeping them: 4 bytes a disc less at each build, the peak of a loose packing's run. Each
// cell's start serves as its fill cursor, ending at the next cell's start; one shift back
// restores the starts (no second array of cells). The order of the discs within a cell changes
// no list (a disc's candidates are put in order of j, the obstacle entries in order of (i, k)).
void Neighbors::sort_by_cell(const Discs& d, long ncell, int nt) {
  const int n = static_cast<int>(d.size());
  cell_start_.assign(ncell + 1, 0);
  order_.resize(n);
  if (nt <= 1 || n < 64 * nt) {  // a few discs: no thread would have a block worth sharing
    for (int i = 0; i < n; ++i)
      if (const long c = grid_.cell_of(d.x[i], d.y[i]); c >= 0) ++cell_start_[c + 1];
    for (long c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
    for (int i = 0; i < n; ++i)
      if (const long c = grid_.cell_of(d.x[i], d.y[i]); c >= 0) order_[cell_start_[c]++] = i;
  } else {
    // Thread t counts and places the discs of its block whose cells are in its rows, from the
    // row of the block's first disc on: the discs are mostly in order of height (lattices and
    // fills are made row by row, and a settled column keeps it), so each thread writes cells no
    // other thread writes. The few others ("strays") are counted and placed after, serially, in
    // thread order, behind each cell's own discs. Serial, the sort is a fifth of a 1M-disc
    // build, most of what two threads could not share.
    const long nx = grid_.nx;
    std::vector<long> first_cell(nt + 1, 0);
    first_cell[nt] = ncell;
    for (int t = 1; t < nt; ++t) {
      const int i = block_start(n, nt, t);
      const long c = grid_.cell_of(d.x[i], d.y[i]);
      first_cell[t] = std::max(first_cell[t - 1], c < 0 ? 0 : c / nx * nx);
    }
    std::vector<Padded<std::vector<int>>> strays(nt);  // per thread: discs outside its rows
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_thread_index();
      const int i0 = block_start(n, nt, t), i1 = block_start(n, nt, t + 1);
      const long c0 = first_cell[t], c1 = first_cell[t + 1];
      std::vector<int>& mine = strays[t].value;
      for (int i = i0; i < i1; ++i) {
        const long c = grid_.cell_of(d.x[i], d.y[i]);
        if (c >= c0 && c < c1) ++cell_start_[c + 1];
        else if (c >= 0) mine.push_back(i);
      }
#pragma omp barrier
#pragma omp single
      {
        for (int u = 0; u < nt; ++u)
          for (int i : strays[u].value) ++cell_start_[grid_.cell_of(d.x[i], d.y[i]) + 1];
        for (long c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
      }  // implied barrier
      for (int i = i0; i < i1; ++i)
        if (const long c = grid_.cell_of(d.x[i], d.y[i]); c >= c0 && c < c1) order_[cell_start_[c]++] = i;
#pragma omp barrier
#pragma omp single
      for (int u = 0; u < nt; ++u)
        for (int i : strays[u].value) order_[cell_start_[grid_.cell_of(d.x[i], d.y[i])]++] = i;
    }
  }
  for (long c = ncell; c > 0; --c) cell_start_[c] = cell_start_[c - 1];
  cell_start_[0] = 0;
}

namespace {
// The room for a new list: the old one's length and a 1/16 margin. The first build has no old
// list to size from: it counts first (count(i0, i1): the pairs of discs [i0, i1)), so that even
// then the list is allocated once at its length.
template <class Count>
std::size_t list_room(std::size_t old_n, int n, int nt, Count&& count) {
  if (old_n != 0) return old_n + old_n / 16 + 64;
  std::size_t c = 0;
  if (nt <= 1) {
    c = count(0, n);
  } else {
#pragma omp parallel for schedule(static) num_threads(nt) reduction(+ : c)
    for (int t = 0; t < nt; ++t) c += count(block_start(n, nt, t), block_start(n, nt, t + 1));
  }
  return c + c / 16 + 64;
}

// The buffer of cap entries: a larger one (first build, or the list grew) with the old list's
// old_n entries at its tail, or the old one with its margin behind them. Where the old entries
// start.
std::size_t old_to_tail(std::vector<PairContact>& pairs, std::size_t cap, std::size_t old_n) {
  if (pairs.capacity() >= cap) {
    pairs.resize(cap);
    return 0;
  }
  std::vector<PairContact> v;
  v.reserve(cap);
  v.resize(cap);
  std::copy(pairs.begin(), pairs.end(), v.end() - static_cast<std::ptrdiff_t>(old_n));
  pairs.swap(v);
  return cap - old_n;
}
}  // namespace

// The pair list is the engine's largest array (about 3 pairs a disc, 24 bytes each). A new list
// built beside the old one would need both at once: twice the largest array, the peak memory of
// a million-disc run. Instead the new list is written over the old one in its own buffer (sized
// with a 1/16 margin at the last build), from the front, in rounds of kRoundDiscs discs a
// thread: each thread searches its part of the round into a small scratch list and takes the
// history from the old entries of the same discs, then the round is copied into place. The old
// entries stay where they are while the new entries of discs below b fit in front of the old
// entries of discs from b on (which are still to be read); when a round would not fit (the list
// grew up to b), the unread old entries are moved once to the buffer's tail, behind the margin,
// and if even that is too little the buffer is enlarged. Moving the whole old list to the tail
// before every build instead would copy the largest array serially at each build (at a million
// discs some 72 MB). The list is the same as a build beside the old one, for any
// thread count.
void Neighbors::build_pairs(const Discs& d, int nt) {
  const int n = static_cast<int>(d.size());
  const std::size_t old_n = pairs.size();
  std::size_t cap = std::max(list_room(old_n, n, nt, [&](int i0, int i1) { return count_pairs(d, i0, i1); }),
                             pairs.capacity());
  // the old entries not yet read: [r, old_end)
  std::size_t r = old_to_tail(pairs, cap, old_n), old_end = r == 0 ? old_n : cap;
  std::size_t w = 0;  // next new entry
  const auto old_from = [&](std::size_t from, int i) {  // first old entry at or after from with disc >= i
    return static_cast<std::size_t>(
        std::lower_bound(pairs.begin() + static_cast<std::ptrdiff_t>(from), pairs.begin() + static_cast<std::ptrdiff_t>(old_end), i,
                         [](const PairContact& c, int k) { return c.i < k; }) - pairs.begin());
  };
  const int threads = std::max(1, nt);
  round_pairs_.resize(threads);
  std::vector<std::size_t> at(threads + 1, 0);
  const int round = kRoundDiscs * threads;
  // One round: thread t's part of the discs [a, b), searched and merged, then copied into place.
  const auto search_part = [&](int t, int a, int b) {
    const int i0 = a + block_start(b - a, threads, t), i1 = a + block_start(b - a, threads, t + 1);
    auto& bp = round_pairs_[t].value;
    bp.clear();
    search_pairs(d, i0, i1, bp);
    const std::size_t from = old_from(r, i0);
    merge_history(pairs.data() + from, pairs.data() + old_end, bp, pair_key);
    at[t + 1] = bp.size();
  };
  const auto place_round = [&](int b) {  // serial: where the round goes, room made if needed
    at[0] = 0;
    for (int u = 0; u < threads; ++u) at[u + 1] += at[u];
    const std::size_t next = old_from(r, b);  // the old entries of discs >= b start here
    const std::size_t need = w + at[threads], rest = old_end - next;
    if (need <= next) {
      r = next;
    } else if (need + rest <= cap) {  // the list grew up to b: the unread old entries to the tail
      std::move_backward(pairs.begin() + static_cast<std::ptrdiff_t>(next), pairs.begin() + static_cast<std::ptrdiff_t>(old_end),
                         pairs.end());
      r = cap - rest;
      old_end = cap;
    } else {  // it grew past the margin: a larger buffer, the unread old entries at its tail
      const std::size_t cap2 = need + rest + (need + rest) / 16 + 64;
      std::vector<PairContact> v;
      v.reserve(cap2);
      v.resize(cap2);
      std::copy(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(w), v.begin());
      std::copy(pairs.begin() + static_cast<std::ptrdiff_t>(next), pairs.begin() + static_cast<std::ptrdiff_t>(old_end),
                v.end() - static_cast<std::ptrdiff_t>(rest));
      pairs.swap(v);
      cap = cap2;
      r = cap2 - rest;
      old_end = cap2;
    }
    for (int u = 0; u < threads; ++u) at[u] += w;
  };
  const auto copy_part = [&](int t) {
    std::copy(round_pairs_[t].value.begin(), round_pairs_[t].value.end(), pairs.begin() + static_cast<std::ptrdiff_t>(at[t]));
  };
  if (threads == 1) {
    for (int a = 0; a < n; a += round) {
      const int b = std::min(n, a + round);
      search_part(0, a, b);
      place_round(b);
      copy_part(0);
      w += round_pairs_[0].value.size();
    }
  } else {
#pragma omp parallel num_threads(threads)
    {
      const int t = omp_thread_index();
      for (int a = 0; a < n; a += round) {
        const int b = std::min(n, a + round);
        search_part(t, a, b);
#pragma omp barrier
#pragma omp single
        place_round(b);  // implied barrier: every thread sees the new places
        copy_part(t);
#pragma omp barrier
#pragma omp single
        w = at[threads - 1] + round_pairs_[threads - 1].value.size();
      }
    }
  }
  pairs.resize(w);
  if (pairs.capacity() > w + w / 8 + 1024) pairs.shrink_to_fit();  // the list shrank (discs removed)
}

template <class F>
void Neighbors::candidates(const Discs& d, int i, F&& f) const {
  const long cell = grid_.cell_of(d.x[i], d.y[i]);
  if (cell < 0) return;
  const long nx = grid_.nx, ny = grid_.ny;
  const long ci = cell % nx, cj = cell / nx;
  const long a0 = std::max(0L, ci - 1), a1 = std::min(nx - 1, ci + 1);
  const double xi = d.x[i], yi = d.y[i], ri = d.r(i);
  // The 3 cells of a row are consecutive in the sorted order: one run of discs per row.
  for (long b = std::max(0L, cj - 1); b <= std::min(ny - 1, cj + 1); ++b) {
    const int s1 = cell_start_[b * nx + a1 + 1];
    for (int s = cell_start_[b * nx + a0]; s < s1; ++s) {
      const int j = order_[s];
      if (j <= i) continue;
      const double dx = d.x[j] - xi, dy = d.y[j] - yi;
      const double reach = ri + d.r(j) + skin;
      if (dx * dx + dy * dy < reach * reach) f(j);
    }
  }
}

std::size_t Neighbors::count_pairs(const Discs& d, int i0, int i1) const {
  std::size_t c = 0;
  for (int i = i0; i < i1; ++i) candidates(d, i, [&](int) { ++c; });
  return c;
}

std::size_t Neighbors::scratch_bytes() const {
  std::size_t b = new_walls_.capacity() * sizeof(WallContact);
  for (const auto& v : round_pairs_) b += v.value.capacity() * sizeof(PairContact);
  return b;
}

void Neighbors::search_pairs(const Discs& d, int i0, int i1, std::vector<PairContact>& out) const {
  for (int i = i0; i < i1; ++i) {
    // Straight into the list, field by field (a push_back of PairContact{i, j} built the entry on
    // the stack in two stores and read it back in one, which the processor cannot forward: a
    // stall at every pair, a third of the search), then a handful of j put in order.
    const std::size_t at = out.size();
    candidates(d, i, [&](int j) {
      PairContact& o = out.emplace_back();
      o.i = i;
      o.j = j;
    });
    PairContact* c = out.data();
    for (std::size_t a = at + 1; a < out.size(); ++a) {  // insertion sort by j (i is the same)
      const int j = c[a].j;
      std::size_t b = a;
      for (; b > at && c[b - 1].j > j; --b) c[b].j = c[b - 1].j;
      c[b].j = j;
    }
  }
}

void Neighbors::search_walls(const Discs& d, const Geometry& g, std::vector<WallContact>& out) const {
  const int nk = g.obstacle_count();
  // The cell along an axis of a box's edge, clamped to the grid (as Grid::cell_of; an infinite
  // edge gives the first or the last cell): a disc inside the box is in a cell of the range.
  const auto along = [&](double v, double lo, long cells) -> long {
    const double f = (v - lo) * grid_.inv_cell;
    if (!(f > 0)) return 0;
    return f < static_cast<double>(cells - 1) ? static_cast<long>(f) : cells - 1;
  };
  for (int k = 0; k < nk; ++k) {
    const Box& b = boxes_[k];
    if (!b.live) continue;
    const long cx0 = along(b.xlo, grid_.xmin, grid_.nx), cx1 = along(b.xhi, grid_.xmin, grid_.nx);
    const long cy0 = along(b.ylo, grid_.ymin, grid_.ny), cy1 = along(b.yhi, grid_.ymin, grid_.ny);
    for (long cy = cy0; cy <= cy1; ++cy) {
      const int s1 = cell_start_[cy * grid_.nx + cx1 + 1];  // a row's cells are consecutive in the order
      for (int s = cell_start_[cy * grid_.nx + cx0]; s < s1; ++s) {
        const int i = order_[s];
        const double xi = d.x[i], yi = d.y[i];
        if (!(xi >= b.xlo && xi <= b.xhi && yi >= b.ylo && yi <= b.yhi)) continue;
        if (obstacle_distance(g, k, xi, yi) < d.r(i) + skin) out.push_back(WallContact{i, k});
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const WallContact& a, const WallContact& c) { return wall_key(a) < wall_key(c); });
}

}  // namespace dem

namespace dem {

void Neighbors::make_ref_boxes(int n) {
  const int nb = (n + kBoxDiscs - 1) / kBoxDiscs;
  ref_boxes_.assign(4 * static_cast<std::size_t>(nb), 0.0f);
  for (int b = 0; b < nb; ++b) {
    float xlo = HUGE_VALF, xhi = -HUGE_VALF, ylo = HUGE_VALF, yhi = -HUGE_VALF;
    for (int i = b * kBoxDiscs; i < std::min(n, (b + 1) * kBoxDiscs); ++i) {
      xlo = std::min(xlo, x0_[i]); xhi = std::max(xhi, x0_[i]);
      ylo = std::min(ylo, y0_[i]); yhi = std::max(yhi, y0_[i]);
    }
    float* box = &ref_boxes_[4 * static_cast<std::size_t>(b)];
    box[0] = xlo; box[1] = xhi; box[2] = ylo; box[3] = yhi;
  }
}

// Patches. A pair is listed when its discs were within r_i + r_j + skin of each other at the
// build; each disc then moves less than skin/2 from its reference position before the lists are
// rebuilt, so an unlisted pair stays apart. The same holds disc by disc: if each disc's reference
// moves to where it is (a patch) only after checking that every disc within r_i + r_j + skin of
// it, by the others' reference positions, is listed with it, an unlisted pair was at least
// r_i + r_j + skin apart when the later of its two references was set, and each disc has moved
// less than skin/2 from its own since. The margin of twice the references' rounding covers the
// floats (the far test's limit is skin/2 less it). Listed pairs that have moved apart stay
// listed, tested apart at each force pass and adding nothing: the forces are those of a rebuilt
// list, the same bits, and a rebuild drops them later. In a discharging silo the lists are
// rebuilt every 11-12 steps for one disc, the one over the gate pushed out through the slit: the
// patch costs a pass over the references instead of a rebuild.
bool Neighbors::patch(const Discs& d, const Geometry& g) {
  const int n = static_cast<int>(d.size());
  if (stale(d) || !(limit2_ > 0) || patch_most <= 0) return false;
  const double ox = grid_.xmin, oy = grid_.ymin;
  const double* __restrict xs = d.x.data(); const double* __restrict ys = d.y.data();
  const float* __restrict rx = x0_.data(); const float* __restrict ry = y0_.data();
  far_.clear();
  // The far test of the moves (World::move_block), a block at a time: a count that vectorises,
  // then the discs of the few blocks that have one.
  for (int b0 = 0; b0 < n; b0 += kBoxDiscs) {
    const int b1 = std::min(n, b0 + kBoxDiscs);
    int count = 0;
    for (int i = b0; i < b1; ++i) {
      const double dx = (xs[i] - ox) - rx[i], dy = (ys[i] - oy) - ry[i];
      count += dx * dx + dy * dy > limit2_ ? 1 : 0;
    }
    if (count == 0) continue;
    if (static_cast<int>(far_.size()) + count > patch_most) return false;
    for (int i = b0; i < b1; ++i) {
      const double dx = (xs[i] - ox) - rx[i], dy = (ys[i] - oy) - ry[i];
      if (dx * dx + dy * dy > limit2_) far_.push_back(i);
    }
  }
  if (far_.empty()) return false;
  // A far disc's new reference is a float like the others, inside the build's extent (whose
  // rounding the limit allows for): rounding_ = sqrt(2) 2^-23 extent.
  const double extent = rounding_ / (std::sqrt(2.0) * std::ldexp(1.0, -23));
  for (int f : far_) {
    const double fx = d.x[f] - ox, fy = d.y[f] - oy;
    if (!(std::abs(fx) <= extent && std::abs(fy) <= extent)) return false;  // NaN included
  }
  std::vector<float> kept;  // the far discs' references, put back if the patch fails
  for (int f : far_) kept.insert(kept.end(), {x0_[f], y0_[f]});
  if (ref_boxes_.empty()) make_ref_boxes(n);
  for (int f : far_) {
    x0_[f] = static_cast<float>(d.x[f] - ox);
    y0_[f] = static_cast<float>(d.y[f] - oy);
    // Its block's box grown to hold it (kept if the patch fails: a box only has to hold its discs).
    float* box = &ref_boxes_[4 * static_cast<std::size_t>(f / kBoxDiscs)];
    box[0] = std::min(box[0], x0_[f]); box[1] = std::max(box[1], x0_[f]);
    box[2] = std::min(box[2], y0_[f]); box[3] = std::max(box[3], y0_[f]);
  }
  const double margin = 2 * rounding_;
  const auto listed = [&](int i, int j) {
    const PairContact key{std::min(i, j), std::max(i, j)};
    return std::binary_search(pairs.begin(), pairs.end(), key,
                              [](const PairContact& a, const PairContact& b) { return pair_key(a) < pair_key(b); });
  };
  bool complete = true;
  for (std::size_t a = 0; a < far_.size() && complete; ++a) {
    const int f = far_[a];
    const double xf = x0_[f], yf = y0_[f], rf = d.r(f);
    const double far_reach = rf + rmax_ + skin + margin;  // no partner beyond it
    for (int b0 = 0; b0 < n && complete; b0 += kBoxDiscs) {
      const float* box = &ref_boxes_[4 * static_cast<std::size_t>(b0 / kBoxDiscs)];
      if (xf < box[0] - far_reach || xf > box[1] + far_reach || yf < box[2] - far_reach || yf > box[3] + far_reach)
        continue;
      for (int j = b0; j < std::min(n, b0 + kBoxDiscs) && complete; ++j) {
        if (j == f) continue;
        const double dx = static_cast<double>(x0_[j]) - xf, dy = static_cast<double>(y0_[j]) - yf;
        const double reach = rf + d.r(j) + skin + margin;
        if (dx * dx + dy * dy < reach * reach && !listed(f, j)) complete = false;
      }
    }
    const int nk = g.obstacle_count(), nw = static_cast<int>(g.walls.size());
    for (int k = 0; k < nk && complete; ++k) {
      if (k < nw && !g.walls[k].active) continue;
      if (!(obstacle_distance(g, k, xf + ox, yf + oy) < rf + skin + margin)) continue;
      const WallContact key{f, k};
      if (!std::binary_search(walls.begin(), walls.end(), key,
                              [](const WallContact& a, const WallContact& b) { return wall_key(a) < wall_key(b); }))
        complete = false;
    }
  }
  if (!complete) {
    for (std::size_t a = 0; a < far_.size(); ++a) {
      x0_[far_[a]] = kept[2 * a];
      y0_[far_[a]] = kept[2 * a + 1];
    }
    return false;
  }
  ++patches;
  return true;
}

void Neighbors::compact(const RemovedDiscs& removed) {
  std::size_t o = 0;
  for (const PairContact& p : pairs) {
    const int i = removed.new_index(p.i), j = removed.new_index(p.j);
    if (i < 0 || j < 0) continue;
    PairContact q = p;
    q.i = i;
    q.j = j;
    pairs[o++] = q;
  }
  pairs.resize(o);
  o = 0;
  for (const WallContact& w : walls) {
    const int i = removed.new_index(w.i);
    if (i < 0) continue;
    WallContact q = w;
    q.i = i;
    walls[o++] = q;
  }
  walls.resize(o);
  ref_boxes_.clear();  // blocks of other discs now
  if (!x0_.empty()) {  // empty: invalidated, rebuilt at the next step
    removed.compact(x0_);
    removed.compact(y0_);
  }
}

}  // namespace dem

namespace dem {

void Neighbors::renumber(const std::vector<int>& new_index) {
  for (PairContact& p : pairs) {
    const int i = new_index[p.i], j = new_index[p.j];
    p.i = std::min(i, j);
    p.j = std::max(i, j);
  }
  std::sort(pairs.begin(), pairs.end(), [](const PairContact& a, const PairContact& b) { return pair_key(a) < pair_key(b); });
  for (WallContact& w : walls) w.i = new_index[w.i];
  ref_boxes_.clear();
  std::sort(walls.begin(), walls.end(), [](const WallContact& a, const WallContact& b) { return wall_key(a) < wall_key(b); });
  if (x0_.size() == new_index.size()) {
    std::vector<float> x(x0_.size()), y(y0_.size());
    for (std::size_t i = 0; i < new_index.size(); ++i) {
      x[new_index[i]] = x0_[i];
      y[new_index[i]] = y0_[i];
    }
    x0_.swap(x);
    y0_.swap(y);
  }
}

}  // namespace dem
