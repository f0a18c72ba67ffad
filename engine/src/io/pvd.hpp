// A ParaView collection (.pvd): the run's snapshots in one animation (File > Open the .pvd),
// each snapshot as parts: the discs, the walls and the contacts at one time.
#pragma once

#include <string>

namespace dem {

class PvdIndex {
 public:
  // A snapshot at time t of files relative to the .pvd's folder: part 0 the discs, 1 the walls,
  // 2 the contacts.
  void add(double t, long step, const std::string& discs, const std::string& walls, const std::string& contacts);
  // Writes the collection atomically to path.
  void write(const std::string& path) const;
  bool empty() const { return entries_.empty(); }
  long last_step() const { return last_step_; }
  // For checkpoints: the entries so far and the step of the last.
  const std::string& entries() const { return entries_; }
  void restore(std::string entries, long last_step) {
    entries_ = std::move(entries);
    last_step_ = last_step;
  }

 private:
  std::string entries_;
  long last_step_ = -1;
};

}  // namespace dem
