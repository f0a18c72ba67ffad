// Section 5(2) of the silo paper: the slit opens under the rested fill; discs fall through,
// are followed below it, and leave the computation at the outlet depth. Records what the paper
// drew (wall forces, flow pictures) and what it could not (series, ratios, jams, patterns).
#pragma once

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "measures/flow.hpp"
#include "measures/wall_loads.hpp"
#include "physics/world.hpp"
#include "io/opening_positions.hpp"
#include "run/phase.hpp"
#include "run/recorder.hpp"
#include "scene/scene.hpp"

namespace dem {

struct BinaryOut;
struct BinaryIn;

// The peaks of a series fed a sample at a time: the largest sample and the largest moving average
// over `win` samples, with the same operations in the same order as over the whole series kept
// (the same bits), but only its last `win` samples in memory (a series per wall bin grew by 8
// bytes a bin and sample: some 32 kB a sample at a million discs).
struct PeakTracker {
  double raw = 0, windowed = 0, acc = 0;
  std::uint64_t count = 0;
  std::vector<double> last;  // the last win samples, sample c at c % win
  void add(double v, std::size_t win) {
    if (last.size() != win) last.assign(win, 0.0);  // the first sample (win is the run's)
    raw = std::max(raw, v);
    acc += v;
    const std::size_t slot = static_cast<std::size_t>(count % win);
    if (count >= win) acc -= last[slot];
    last[slot] = v;
    if (count + 1 >= win) windowed = std::max(windowed, acc / static_cast<double>(win));
    ++count;
  }
};

// Everything a discharge carries from step to step besides the world: the state at opening,
// the series and logs so far, the loop position. Checkpoints save it (checkpoint.hpp).
struct DischargeState {
  // At opening.
  double t_open = 0;         // [s] world time
  int n_initial = 0;
  double rmean = 0;          // [cm] mean radius at opening (surface sinking)
  double fill_top = -1e300;
  double surf0[3] = {0, 0, 0};  // surface of the wall, centre and wall columns
  OpeningPositions at_open;     // positions at opening, by disc id (a file beside the outputs)
  std::vector<WallLoad> static_walls;
  // Running.
  long next_s = 0;           // next loop step (steps since opening)
  Status status = Status::running;
  std::vector<Removal> removals;
  double jam_at = -1;
  int jams = 0;
  double sink_time[3] = {0, 0, 0};
  // The wall series (a row per wall, bin and sample: at a million discs some 0.4 MB a sample) go
  // to OUT/wall_series.csv.tmp as they are sampled, renamed when the discharge ends; a checkpoint
  // holds the file's length, to which a resumed run cuts it. The other series are a row or a few
  // a sample, kept as text.
  std::uint64_t series_bytes = 0;
  std::ofstream series_out;
  std::ostringstream totals, flow;  // the text of the other series files
  std::vector<std::vector<PeakTracker>> bin_peaks;  // per wall and bin: peaks of the normal force
  std::vector<PeakTracker> total_peaks;             // per wall: peaks of the total normal force
  std::vector<double> sample_t;
  std::size_t next_snap = 0;
  double last_removal = 0, removed_mass = 0, moved_fraction = 0;

  void save(BinaryOut& o) const;
  void load(BinaryIn& r);
};

// Section 5(2) as a phase of the run (phase.hpp): begin records the state at opening, removes
// the gate and samples t = 0; each step then removes the discs below the outlet, watches for
// jams (note 4's keystone removal when asked), samples the series and writes the snapshots;
// finish writes the series files and the metrics (docs/outputs.md).
// Where the slit is and where discs leave (from the scene and the walls, the same at every resume).
struct DischargeFrame {
  double slit_left = 0, slit_right = 0, floor = 0;  // the gate's ends (or the points L and R)
  double width = 0, x_left = 0, x_right = 0, xc = 0, top = 0;
  double y_out = 0;  // discs below it leave (discharge.outlet_depth under the slit)
  double g = 0;
};

// What a finished discharge gives its caller (the same values as its metrics, typed).
struct DischargeOutcome {
  Status status = Status::running;
  double duration = 0;          // [s] simulated since opening
  std::size_t removed = 0;      // discs out (outlet and keystones)
  int out_at_1s = 0;            // through the outlet by 1 s after opening
  double flow_rate_discs = 0;   // [discs/s] NaN with fewer than 10 removals
  std::string pattern;          // funnel, piping or undetermined
  double peak_ratio_bottom = 0, peak_ratio_side = 0;
};

class DischargePhase : public Phase {
 public:
  DischargePhase(const SceneSpec& spec, std::string out_dir);
  const char* name() const override { return "discharge"; }
  void attach(World& w) override;
  Status begin(World& w, std::string& reason) override;
  void before_step(World& w, bool stopping) override;
  Status after_step(World& w) override;
  bool pays_own_kick() const override { return true; }
  void finish(World& w, Status status) override;
  std::string progress(const World& w) const override;
  double fraction(const World& w) const override;
  void flush() override;
  void save(BinaryOut& o) const override { st.save(o); }
  void load(BinaryIn& r) override { st.load(r); }
  nlohmann::ordered_json metrics() const override { return metrics_; }
  const DischargeOutcome& outcome() const { return outcome_; }

  // Why a discharge resumed from a checkpoint cannot go on with its wall series file ("" : it can).
  std::string series_file_problem() const;
  // The positions at opening (kept in a file of the output directory, removed at the end).
  OpeningPositions& at_open() { return st.at_open; }
  const std::vector<Removal>& removals() const { return st.removals; }
  double duration(const World& w) const { return w.time - st.t_open; }

  DischargeState st;
  Recorder* record = nullptr;  // the run's (set before begin): writes each snapshot's files

 private:
  void sample(World& w, double t);
  void snapshots(World& w, double t);
  const SceneSpec& spec_;
  std::string out_;
  std::string series_path_, series_tmp_;
  // Derived at attach (the same at every resume).
  DischargeFrame f_;
  long steps_total_ = 0, sample_every_ = 1;
  std::size_t win_ = 1;
  RemovedDiscs dead_;  // the discs leaving at a step: a few indices, not a mask of all discs
  DischargeOutcome outcome_;
  nlohmann::ordered_json metrics_;
};

}  // namespace dem
