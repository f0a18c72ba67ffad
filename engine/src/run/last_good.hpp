// The last state a run checked and found sound: what an unstable run writes
// in place of its final state. Kept in a file beside the outputs (set_file), not in memory: as
// a copy in memory it would be, after the pair list, the largest array of a million-disc run (48
// bytes a disc). Without a file (library use, tests) it is kept in memory, as the same bytes.
#pragma once

#include <string>

#include "physics/discs.hpp"

namespace dem {

struct BinaryOut;
struct BinaryIn;

// Runs keep their last good state every kKeepEvery steps, after a check that passed (fill,
// discharge, shear).
constexpr long kKeepEvery = 1000;
// Worlds of fewer discs keep it in memory (48 bytes a disc: 480 kB at most): for them a file's
// write and rename would cost as much as the 1000 steps between keeps (350 discs: 4 ms against
// 7 ms; the run.log's loop timing showed it as the checks' share).
constexpr std::size_t kLastGoodInFileFrom = 10000;

class LastGood {
 public:
  // Where to keep it ("" : in memory). A file already there is replaced at the next keep.
  void set_file(const std::string& path) { path_ = path; }
  const std::string& file() const { return path_; }
  // Every per-disc array of d (state.hpp's write_discs), at simulated time t [s]. A file is
  // written whole and then renamed over the last one: a run killed meanwhile leaves either.
  void keep(const Discs& d, double t);
  bool has() const { return has_; }
  double time() const { return time_; }
  // The discs as kept (a discharge may have removed some since). Throws std::runtime_error
  // naming the file when it cannot be read back.
  Discs load() const;
  // Checkpoints carry it (its time and bytes), so a resumed run can still rewind.
  void write_to(BinaryOut& o) const;
  void read_from(BinaryIn& r);
  // Forget it; its file is removed (a run that ended without needing it).
  void discard();

 private:
  std::string path_;
  std::string bytes_;  // in-memory keeping only
  bool has_ = false;
  double time_ = 0;
};

}  // namespace dem
