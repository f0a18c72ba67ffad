// The simple shear test of paper 2 (Sumita, Kiyama & Nishimura): a box b wide, the discs in a
// regular arrangement (with or without clusters), a rigid top plate with its own weight that
// moves vertically and horizontally but does not rotate; after compression under the plate the
// left and right walls stay parallel and turn about their lower ends at a constant rate.
// Stresses on virtual horizontal planes (stress_planes.hpp) against the shear strain.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run/phase.hpp"
#include "run/recorder.hpp"
#include "scene/shear_spec.hpp"

namespace dem {

class World;
struct SceneSpec;

// What a finished shear gives its caller (the same values as its metrics, typed).
struct ShearOutcome {
  std::size_t samples = 0;
  double strain_final = 0, peak_ratio = 0, strain_at_peak = 0, peak_ratio_windowed = 0, sigma_initial = 0;
};

// One sample of the shear: the mean over the virtual planes (stress_planes.hpp).
struct ShearSample {
  double t, strain, sigma, tau, ratio;
  double sigma_check, tau_check, sigma_inertia, tau_inertia;
};

// The shear as a phase of the run (phase.hpp): the side walls turn at shear.rate until
// shear.max_strain; every shear.sample_strain the plane stresses are sampled, at the
// shear.snapshots strains the discs and contacts are written; finish writes shear_series.csv,
// shear_planes.csv, snapshots/index.json and the metrics (docs/outputs.md, "Shear outputs").
class ShearPhase : public Phase {
 public:
  ShearPhase(const SceneSpec& spec, std::string out_dir) : spec_(spec), out_(std::move(out_dir)) {}
  const char* name() const override { return "shear"; }
  void attach(World& w) override;
  Status begin(World& w, std::string& reason) override;
  void before_step(World& w, bool stopping) override;
  Status after_step(World& w) override;
  void finish(World& w, Status status) override;
  std::string progress(const World& w) const override;
  double fraction(const World& w) const override;
  void save(BinaryOut& o) const override;
  void load(BinaryIn& r) override;
  nlohmann::ordered_json metrics() const override { return metrics_; }
  const ShearOutcome& outcome() const { return outcome_; }

  Recorder* record = nullptr;  // the run's (set before begin): writes each snapshot's files

 private:
  Status at_strain(World& w);  // the sample and snapshots due at the current strain; the end test
  void sample(World& w, double strain);
  void snapshot(World& w, double strain);
  const SceneSpec& spec_;
  std::string out_;
  // Derived at attach (the same at every resume).
  int plate_ = -1, left_ = -1, right_ = -1, floor_ = -1;
  double weight_ = 0, plate_weight_ = 0;
  // The shear's own state (checkpoints carry it).
  long step_ = 0, max_steps_ = 0, next_sample_ = 0;
  std::size_t next_snap_ = 0;
  double t0_ = 0;                 // [s] world time at the shear's start
  int n_rows_ = 0;
  std::vector<int> row_;          // each disc's row at the start (the planes lie between rows)
  std::vector<ShearSample> samples_;
  std::string series_, planes_;   // the text of shear_series.csv and shear_planes.csv so far
  nlohmann::ordered_json snaps_ = nlohmann::ordered_json::array();
  ShearOutcome outcome_;
  nlohmann::ordered_json metrics_;
};

}  // namespace dem
