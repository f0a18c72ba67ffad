// The total normal force f_n (eq. 9) of each disc pair at the end of the last step, kept for
// velocity_verlet_onset under friction_cap = "total" alone: its slip correction needs the Coulomb
// cap mu |f_n| at a step's start exactly (onset.cpp), and a pair's history is e_n, e_s only
// (PairContact stays 24 bytes for every scene).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "physics/discs.hpp"

namespace dem {

// Records of the pairs that touched at the end of the last force pass, sorted by (i, j): 16 bytes
// a touching pair (twice: the last pass's and the one being written), nothing for a scene that
// does not use them. Only touching pairs are recorded, and a touching pair is in every neighbour
// list, so a list build changes no record; removals and re-sorts renumber them as they do the
// lists; state files and checkpoints carry them.
class PairNormals {
 public:
  struct Record {
    std::uint64_t key;  // i << 32 | j, i < j: the pair list's order is the keys' (one compare)
    double fn;
    int i() const { return static_cast<int>(key >> 32); }
    int j() const { return static_cast<int>(key & 0xffffffffu); }
  };
  static std::uint64_t key(int i, int j) {
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32 | static_cast<std::uint32_t>(j);
  }

  std::size_t size() const { return n_; }
  const Record* begin() const { return now_.data(); }
  const Record* end() const { return now_.data() + n_; }
  std::vector<Record> records() const { return {begin(), end()}; }
  bool allocated() const { return now_.capacity() > 0 || next_.capacity() > 0; }

  // A force pass in list order reads the last pass's records with a cursor (`last`) and writes
  // its own through raw pointers (the pass's loop keeps them in registers): from start_pass() up
  // to room_end(), grow() when full, end_pass(at) with the position after the last one written.
  // The record of the pair with key k at the end of the last pass (nullptr: it did not touch
  // then); `at` from begin(), asked in key order.
  static const Record* last(const Record*& at, const Record* end, std::uint64_t k) {
    while (at < end && at->key < k) ++at;
    return at < end && at->key == k ? at : nullptr;
  }
  Record* start_pass();
  Record* room_end() { return next_.data() + next_.size(); }
  Record* grow(Record* at);  // the records before `at` kept; the new position of `at`
  void end_pass(const Record* at);

  void clear();  // frees both
  // Drops the records of pairs with a removed disc and renumbers the discs (order kept).
  void compact(const RemovedDiscs& removed);
  // The discs were put in a new order (disc i is now new_index[i]): sorted by (i, j) again.
  void renumber(const std::vector<int>& new_index);
  // Records read from a state file (sorted by (i, j), i < j: the reader checks).
  void assign(std::vector<Record> records);

 private:
  std::vector<Record> now_;   // the last pass's records: [0, n_)
  std::vector<Record> next_;  // this pass's buffer (its size is its room)
  std::size_t n_ = 0;
};

}  // namespace dem
