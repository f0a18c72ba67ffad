// The total normal force f_n (eq. 9) of each disc pair at the end of the last step, kept for
// velocity_verlet_onset under friction_cap = "total" alone: its slip correction needs the Coulomb
// cap mu |f_n| at a step's start exactly (onset.cpp), and a pair's history is e_n, e_s only
// (PairContact stays 24 bytes for every scene).
#pragma once

#include <cstddef>
#include <vector>

#include "physics/discs.hpp"

namespace dem {

// Records of the pairs that touched at the end of the last force pass, sorted by (i, j): 16 bytes
// a touching pair, nothing for a scene that does not use them. Only touching pairs are recorded,
// and a touching pair is in every neighbour list, so a list build changes no record; removals and
// re-sorts renumber them as they do the lists; state files and checkpoints carry them.
class PairNormals {
 public:
  struct Record {  // i < j
    int i, j;
    double fn;
  };

  const std::vector<Record>& records() const { return now_; }
  std::size_t size() const { return now_.size(); }
  bool allocated() const { return now_.capacity() > 0 || next_.capacity() > 0; }

  // A force pass in list order: the f_n the pair (i, j) had at the end of the last pass (nullptr:
  // it did not touch then), with one cursor `at` from 0; the pass keeps this step's with keep
  // and replaces the last step's with end_pass.
  const double* last(int i, int j, std::size_t& at) const {
    const std::size_t n = now_.size();
    while (at < n && (now_[at].i < i || (now_[at].i == i && now_[at].j < j))) ++at;
    return at < n && now_[at].i == i && now_[at].j == j ? &now_[at].fn : nullptr;
  }
  void start_pass() { next_.clear(); }
  void keep(int i, int j, double fn) { next_.push_back(Record{i, j, fn}); }
  void end_pass() { now_.swap(next_); }

  void clear();  // frees both
  // Drops the records of pairs with a removed disc and renumbers the discs (order kept).
  void compact(const RemovedDiscs& removed);
  // The discs were put in a new order (disc i is now new_index[i]): sorted by (i, j) again.
  void renumber(const std::vector<int>& new_index);
  // Records read from a state file (sorted by (i, j), i < j: the reader checks).
  void assign(std::vector<Record> records);

 private:
  std::vector<Record> now_;   // the last pass's
  std::vector<Record> next_;  // this pass's, as it runs (its buffer kept between passes)
};

}  // namespace dem
