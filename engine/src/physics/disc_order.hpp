// When the disc arrays are put in cell order, and that order. The force pass reads x[j], y[j]
// and the kinds of every candidate j of disc i; with the discs in the order of a lattice or of
// the cells, j is a few rows of discs from i and those reads hit the cache; in a random order (a
// file fill of any order) they miss: 2.7x the time a step at 100k settled discs
// (benchmarks/README.md, "Disc order").
//
// The measure is the mean index gap j - i (i < j) of the pairs in contact, in units of the discs
// of one row of cells (n / rows): the spread. A pair is in contact when its discs overlap now
// (the test of eq. 3), not when it has a history: a packing read from a file starts with
// overlaps and no history, and is measured, and re-sorted, at step 0. A lattice filled row by row and
// the cell order both have a spread under 1 (a disc's partners are in its row of cells or the
// next, that row's discs further on); a random order has about rows / 3 (a random pair's gap is
// (n + 1) / 3). The rule reads only what every run of the world has at that step, whatever its
// thread count and whether it was resumed from a state file (whose lists are built again at
// the restart, with other candidates): the positions, and of the candidates those that overlap. It is evaluated every kCheckEvery steps, at the start of the step, so the re-sorts
// come at the same steps in all of them.
#pragma once

#include <cstddef>
#include <vector>

#include "physics/discs.hpp"
#include "physics/neighbors.hpp"

namespace dem {

enum class DiscOrder {
  automatic,  // re-sort every kCheckEvery steps when the spread exceeds kMaxSpread
  off         // the discs keep the order they were given in
};

struct DiscOrderRule {
  // Re-sort above this spread: 2 leaves room for a settled packing's order to age (its discs
  // move between cells) before a re-sort, and is far below a random order's rows / 3 in a silo
  // of more than a few rows of cells.
  static constexpr double kMaxSpread = 2.0;
  // Worlds of fewer discs are not re-sorted: their arrays (about 100 bytes a disc) fit in the
  // caches whatever their order.
  static constexpr std::size_t kMinDiscs = 4096;
  // Steps between evaluations (a multiple of World::kRebalanceEvery): a pass over the pair list,
  // some 1/300 of a step's time at this interval.
  static constexpr long kCheckEvery = 256;
};

// The grid of the order: square cells of side max(min_cell, 2 r_max + skin) (the lists' own
// size) over the discs' extent now, coarsened to at most 4 n + 64 cells as the lists' grid is.
// It is made from the positions alone, not taken from the last list build (whose time differs
// between a resumed run and the run in one piece).
struct OrderGrid {
  double xmin = 0, ymin = 0, inv_cell = 1;
  long nx = 1, ny = 1;
  long cell_of(double x, double y) const;  // row-major; nx * ny for a non-finite position
};
OrderGrid order_grid(const Discs& d, double skin, double min_cell);

// The discs in the grid's row-major cell order, within a cell by x (then by index), non-finite
// ones last: order[s] is the disc to put at index s. Each row of cells is then in x order, a
// zigzag over the one or two rows of discs it holds, as regular as a lattice filled row by row;
// by index within a cell, a shuffled fill put in this order ran 1.16-1.18x the row-by-row
// packing's time a step, by x 0.97-0.99x (benchmarks/README.md, "Disc order").
std::vector<int> cell_order(const Discs& d, const OrderGrid& g);

// The spread of the candidate pairs whose discs overlap, over the discs in `rows` rows of cells
// (0 without such pairs).
double disc_order_spread(const std::vector<PairContact>& pairs, const Discs& d, long rows);
// Whether the discs should be put in cell order now.
bool disc_order_degraded(const std::vector<PairContact>& pairs, const Discs& d, long rows);

const char* to_string(DiscOrder o);

}  // namespace dem
