// The fill: the discs fall and settle until rest (the paper's note 3) or end.time.
#pragma once

#include "run/phase.hpp"

namespace dem {

struct SceneSpec;

// The rest measure of the fill (summary.json "rest").
struct Rest {
  bool reached = false;
  double time = 0;        // [s] simulated time when rest was first detected
  double threshold = 0;   // rest_factor * g dt^2 [cm]
  double mean_abs_du = 0, mean_abs_dv = 0;  // last measured (x and y increments per step)
};

class FillPhase : public Phase {
 public:
  explicit FillPhase(const SceneSpec& spec) : spec_(spec) {}
  const char* name() const override { return "fill"; }
  void attach(World& w) override;
  Status begin(World& w, std::string& reason) override;
  void before_step(World& w, bool stopping) override;
  Status after_step(World& w) override;
  bool pays_own_kick() const override { return true; }
  void finish(World& w, Status status) override;
  std::string progress(const World& w) const override;
  double fraction(const World& w) const override;

  Rest rest;  // the checkpoint carries it beside the runner's state (checkpoint.hpp)

 private:
  const SceneSpec& spec_;
  long max_steps_ = 0;
};

}  // namespace dem
