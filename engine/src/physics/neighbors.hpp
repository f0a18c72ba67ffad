// Contact detection: a sorted cell grid (counting sort, the paper's eq. (27) cells in row-major
// order) builds Verlet lists with a skin, so lists are rebuilt only when some disc has moved
// more than skin/2. Contact history (the incremental springs) is carried across rebuilds by
// merging the old and new sorted lists. Nothing here is O(N^2).
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include "physics/discs.hpp"
#include "physics/geometry.hpp"
#include "physics/parallel.hpp"

namespace dem {

// One candidate disc-disc pair (i < j) and its history.
// The history the next step needs, and nothing else: 24 bytes a pair. The total forces f_n, f_s
// are outputs, recorded only for the force passes whose results are written (World::pair_totals).
struct PairContact {
  int i, j;
  double en = 0, es = 0;  // elastic normal and shear forces, eqs. (7a), (11a)
};

// One candidate disc-obstacle contact (obstacle k: walls first, then points).
struct WallContact {
  int i, k;
  double en = 0, es = 0;
  double fn = 0, fs = 0;
  double px = 0, py = 0;  // last contact point on the obstacle
  double nx = 0, ny = 0;  // last unit normal from the disc to the obstacle
  bool touching = false;
};

class Neighbors {
 public:
  double skin = 0.2;      // [cm] extra reach of the lists
  double min_cell = 0.0;  // [cm] requested cell size (0: 2 r_max + skin)

  std::vector<PairContact> pairs;  // sorted by (i, j)
  std::vector<WallContact> walls;  // sorted by (i, k)
  long rebuilds = 0;

  // The lists are not for these discs (never built, invalidated, or another count): rebuild.
  bool stale(const Discs& d) const { return x0_.size() != d.size(); }
  // Past skin/2 from its position at the last rebuild a disc may have a partner the lists miss
  // (two discs approaching each other use up the skin). The drifts ask it of the discs they have
  // just moved (World::move_block): a disc is far when (x - origin_x - x0)^2 + (...)^2 exceeds
  // moved_far_limit2(). The reference positions are floats, relative to the grid's corner (8
  // bytes a disc less, 4 % of a million-disc run); the limit is skin/2 less their largest
  // rounding, so every disc that has really moved skin/2 is caught (a rebuild may come a little
  // earlier, which changes no force: apart pairs contribute nothing).
  double moved_far_limit2() const { return limit2_; }
  double origin_x() const { return grid_.xmin; }
  double origin_y() const { return grid_.ymin; }
  // New lists with the history of the old ones carried over; nt threads give the same lists.
  void rebuild(const Discs& d, const Geometry& g, int nt = 1);
  // The lists kept when at most patch_most discs are far and every candidate of theirs is
  // already listed: each far disc's reference position moves to where it is, and nothing else
  // changes (neighbors.cpp, "Patches"). False: nothing changed, rebuild. Fixed obstacles only.
  bool patch(const Discs& d, const Geometry& g);
  int patch_most = 4;  // far discs a patch takes at most (0: every far disc rebuilds the lists)
  long patches = 0;
  double cell_size() const { return cell_; }
  // Bytes of the list scratch kept between builds (round pair lists, obstacle lists): about
  // kRoundDiscs discs' worth a thread, whatever the number of discs.
  std::size_t scratch_bytes() const;
  // Discs were removed (order kept): the lists stay sorted and the history stays attached.
  void compact(const RemovedDiscs& removed);
  // The discs were put in a new order (disc i is now new_index[i]): the lists and the reference
  // positions follow them. A pair whose discs swap order is stored as (j, i): its history is the
  // same seen from either disc (e_n, e_s are symmetric in (4), (5), (15)).
  void renumber(const std::vector<int>& new_index);
  // Forget the reference positions: the next step rebuilds (after geometry changes).
  void invalidate() { x0_.clear(); y0_.clear(); ref_boxes_.clear(); }
  // The positions of the last rebuild and the cell size: with the lists, what a checkpoint
  // needs to continue exactly as if never stopped (same lists, same rebuild steps).
  const std::vector<float>& reference_x() const { return x0_; }
  const std::vector<float>& reference_y() const { return y0_; }
  struct Reference {  // what the skin/2 test reads besides the floats
    double cell, ox, oy, limit2;
  };
  Reference reference() const { return {cell_, grid_.xmin, grid_.ymin, limit2_}; }
  void restore_reference(std::vector<float> x0, std::vector<float> y0, const Reference& r) {
    x0_ = std::move(x0);
    y0_ = std::move(y0);
    cell_ = r.cell;
    grid_.xmin = r.ox;  // the rest of the grid serves builds only
    grid_.ymin = r.oy;
    limit2_ = r.limit2;
    rounding_ = 0.5 * skin - std::sqrt(limit2_);  // as the build set the limit from it
    rmax_ = HUGE_VAL;  // unknown here: a patch then searches every block (until the next build)
    ref_boxes_.clear();
  }

 private:
  std::vector<float> x0_, y0_;  // positions at the last rebuild, less the grid's corner
  double limit2_ = 0;           // see moved_far_limit2
  double rounding_ = 0;         // [cm] the reference positions' largest rounding (the build's extent)
  std::vector<int> far_;        // a patch's far discs
  // A patch's search: the box of the reference positions of each block of kBoxDiscs discs (in
  // the arrays' order, which is mostly cell order: a block is a short stretch of a row of cells),
  // xlo, xhi, ylo, yhi; empty when stale (a build, a removal, a re-sort), made by the next patch.
  static constexpr int kBoxDiscs = 256;
  std::vector<float> ref_boxes_;
  double rmax_ = 0;             // [cm] the largest radius at the build (removals only lower it)
  void make_ref_boxes(int n);
  double cell_ = 0;
  // Scratch kept between rebuilds to avoid reallocation.
  std::vector<int> cell_start_, order_;
  std::vector<WallContact> new_walls_;
  std::vector<Padded<std::vector<PairContact>>> round_pairs_;  // per thread: one round's new pairs
  static constexpr int kRoundDiscs = 4096;  // discs a thread searches per round of build_pairs
  struct Box {  // an obstacle's bounding box grown by the largest disc reach
    double xlo, xhi, ylo, yhi;
    bool live;  // false: an inactive wall, never a candidate
  };
  std::vector<Box> boxes_;
  struct Grid {
    double xmin = 0, ymin = 0, inv_cell = 1;  // inv_cell: 1 / cell size
    long nx = 0, ny = 0;
    // The row-major cell of a disc at (x, y), -1 for a non-finite position (in no cell). In
    // double (x87 long double here costs a control-word switch per conversion: 4x the build),
    // by the inverse (a division costs the build 12 %: this runs three times a disc);
    // x >= xmin, and a quotient past the grid (or inf / NaN from extreme extents) is clamped
    // before it is converted. Rounding can put a disc in the next cell only within ~1e-16 of a
    // cell edge, far inside the skin (the moved-far limit is also 2^-23 of the extent short).
    long cell_of(double x, double y) const {
      if (!std::isfinite(x) || !std::isfinite(y)) return -1;
      const double fx = (x - xmin) * inv_cell, fy = (y - ymin) * inv_cell;
      const long cx = fx < static_cast<double>(nx - 1) ? static_cast<long>(fx) : nx - 1;
      const long cy = fy < static_cast<double>(ny - 1) ? static_cast<long>(fy) : ny - 1;
      return cy * nx + cx;
    }
  } grid_;
  // The discs by cell: order_, and cell_start_ for ncell cells (nt threads, the same cells).
  void sort_by_cell(const Discs& d, long ncell, int nt);
  // The new pair list, written over the old one (see neighbors.cpp).
  void build_pairs(const Discs& d, int nt);
  // Candidate pairs of discs [i0, i1) from the sorted cells, sorted by (i, j).
  void search_pairs(const Discs& d, int i0, int i1, std::vector<PairContact>& out) const;
  // Candidate obstacles of every disc, sorted by (i, k): the discs of the cells under each
  // obstacle's box (one serial search of a few cells: a disc-by-disc test of every box is 8 % of
  // a build).
  void search_walls(const Discs& d, const Geometry& g, std::vector<WallContact>& out) const;
  template <class F>
  void candidates(const Discs& d, int i, F&& f) const;  // f(j) for each candidate j > i, unsorted
  std::size_t count_pairs(const Discs& d, int i0, int i1) const;  // candidates of discs [i0, i1)
};

}  // namespace dem
