// The positions of a discharge's discs at the opening of the slit, by disc id: what the moved
// fraction (flow_series.csv) and the snapshots' displacements are measured from. Kept in a file
// beside the outputs (set_file), not in memory, where at a million discs they would be 16 bytes a
// disc of the peak; read back in blocks. Without a file (library use, tests) kept in memory.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "physics/discs.hpp"

namespace dem {

struct BinaryOut;
struct BinaryIn;

class OpeningPositions {
 public:
  // Where to keep them ("" : in memory).
  void set_file(const std::string& path) { path_ = path; }
  // d's positions, by id (ids without a disc read NaN). The file: magic DEMOPEN1, a uint64 count
  // of ids, then x, y per id (float64, this machine's byte order).
  void keep(const Discs& d);
  std::uint64_t size() const { return count_; }  // ids covered: the largest id + 1

  // Reads them back, a block of ids at a time: cheapest in increasing id order (the discs' order).
  class Reader {
   public:
    explicit Reader(const OpeningPositions& p) : p_(p) {}
    // Throws std::runtime_error naming the file when it cannot be read, std::out_of_range for an
    // id not covered.
    void at(int id, double& x0, double& y0);

   private:
    const OpeningPositions& p_;
    std::vector<double> block_;  // x, y of ids [first_, first_ + block_.size() / 2)
    std::uint64_t first_ = 0;
  };

  // Checkpoints carry them (count and values).
  void write_to(BinaryOut& o) const;
  void read_from(BinaryIn& r);
  // Forget them; the file is removed (the discharge is over).
  void discard();

 private:
  static constexpr std::uint64_t kBlock = 1 << 16;  // ids a read brings in (1 MB)
  static constexpr std::uint64_t kHeader = 16;      // magic and count
  std::string path_;
  std::vector<double> xy_;  // in-memory keeping only
  std::uint64_t count_ = 0;
};

}  // namespace dem
