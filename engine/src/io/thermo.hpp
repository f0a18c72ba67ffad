// thermo.csv (docs/outputs.md): a row of the run's global measures every output.thermo_interval
// of simulated time and at each phase's start and end, in every phase. Computed only at those
// steps, from what the step left (no cost on the other steps).
#pragma once

#include <string>
#include <vector>

namespace dem {

class World;
struct GroupLoads;

class Thermo {
 public:
  // The wall groups of its columns: those of the world's walls in their first order, fixed at
  // the first call.
  const std::vector<std::string>& groups(const World& w);
  // Appends the row of the world as it is, in `phase`, with `loads` measured over groups(w) (the
  // header first).
  void sample(const World& w, const char* phase, const GroupLoads& loads);
  // The file's text so far (its header included).
  const std::string& text() const { return text_; }
  long last_step() const { return last_step_; }
  // From a checkpoint: the text so far and the step of its last row.
  void restore(std::string text, long last_step) {
    text_ = std::move(text);
    last_step_ = last_step;
  }

 private:
  std::vector<std::string> groups_;
  std::string text_;
  long last_step_ = -1;
};

}  // namespace dem
