// The total forces of the pairs that touched in a recorded force pass (outputs, not history).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "physics/discs.hpp"
#include "physics/neighbors.hpp"

namespace dem {

// The total forces f_n, f_s (eqs. 9, 14) of a touching pair in a recorded force pass, with its
// discs: the explicit record (state files, the arch search's tests).
struct PairForce {
  int i, j;
  double fn, fs;
};

// The totals of the pairs that touched in one recorded force pass, in the pair list's order
// (sorted by (i, j)). While the list is the one that pass ran over ("bound"), a total's pair is
// a bit over the list: 16 bytes a touching pair and one bit a listed pair, where (i, j) with each
// takes 24 (7 MB less at a million discs, where an output step's totals set the run's peak).
// Before that list is built again (a build right after the recorded pass) the (i, j) of each
// total are written beside it ("detached", 24 bytes a pair); totals read from a state file are
// detached too. Removals keep either form (the totals of the removed discs' pairs go with them).
class PairTotals {
 public:
  struct Force {
    double fn, fs;
  };
  struct Cursor {  // a walk over the current list in order (PairTotals::at)
    std::size_t p = 0, r = 0;
  };

  bool empty() const { return f_.empty(); }
  std::size_t size() const { return f_.size(); }
  std::size_t capacity() const { return f_.capacity(); }
  bool detached() const { return detached_; }
  bool allocated() const { return f_.capacity() > 0 || !bits_.empty() || !ij_.empty(); }

  // A recorded pass over a list of list_size pairs, count of them touching: room for exactly
  // count totals and a cleared bit a pair (the old totals freed first, never both held). The
  // pass writes the totals in list order from forces() and sets the bit of each touching pair.
  void start(std::size_t count, std::size_t list_size);
  Force* forces() { return f_.data(); }
  std::uint64_t* bits() { return bits_.data(); }
  void clear();  // frees everything

  // Writes the (i, j) of each total from `pairs`, the list the pass ran over (call before it changes).
  void detach(const std::vector<PairContact>& pairs);
  // Drops the totals of pairs with a removed disc and renumbers the discs, as Neighbors::compact
  // does to `pairs` (call with the list before it).
  void compact(const std::vector<PairContact>& pairs, const RemovedDiscs& removed);
  // The discs were put in a new order (disc i is now new_index[i]; World::resort_discs): detached
  // totals follow them, sorted by (i, j) again. Bound totals are detached first (`pairs`, the
  // list they are over, before it is renumbered).
  void renumber(const std::vector<PairContact>& pairs, const std::vector<int>& new_index);
  // Explicit records, sorted by (i, j): the detached form (state files, tests). assign is
  // start_detached(size) and a push of each.
  void assign(const std::vector<PairForce>& records);
  void start_detached(std::size_t count);  // empty, room for count records
  void push(const PairForce& q) {
    f_.push_back({q.fn, q.fs});
    ij_.push_back({q.i, q.j});
  }
  std::vector<PairForce> records(const std::vector<PairContact>& pairs) const;

  // f(i, j, fn, fs) for each total, in (i, j) order; `pairs` is the current list.
  template <class F>
  void each(const std::vector<PairContact>& pairs, F&& f) const {
    if (detached_) {
      for (std::size_t r = 0; r < f_.size(); ++r) f(ij_[r][0], ij_[r][1], f_[r].fn, f_[r].fs);
      return;
    }
    if (!allocated()) return;  // nothing recorded
    check_list(pairs);
    std::size_t r = 0;
    for (std::size_t w = 0; w < bits_.size(); ++w)
      for (std::uint64_t b = bits_[w]; b != 0; b &= b - 1) {
        const PairContact& c = pairs[w * 64 + static_cast<std::size_t>(__builtin_ctzll(b))];
        f(c.i, c.j, f_[r].fn, f_[r].fs);
        ++r;
      }
  }
  // The totals of pair p of the current list `pairs` (nullptr: apart in the recorded pass, or not
  // in it): ask in list order with one cursor (a smaller p than the last starts it again).
  const Force* at(const std::vector<PairContact>& pairs, std::size_t p, Cursor& c) const;

 private:
  // Bound totals: the list is still the pass's (a bug otherwise: logic_error). Not allocated
  // (nothing recorded, or cleared): no list to check, nothing to read.
  void check_list(const std::vector<PairContact>& pairs) const;
  bool bit(std::size_t p) const { return (bits_[p >> 6] >> (p & 63)) & 1u; }
  std::vector<Force> f_;
  std::vector<std::uint64_t> bits_;         // bound: bit p of the list's pair p
  std::vector<std::array<int, 2>> ij_;      // detached: the discs of each total
  std::size_t list_size_ = 0;               // bound: the size of the list the bits are over
  bool detached_ = false;
};

}  // namespace dem
