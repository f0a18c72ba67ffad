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

#include "run/control.hpp"
#include "run/last_good.hpp"
#include "run/opening_positions.hpp"
#include "io/outputs.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace dem {

struct Removal {
  double t;          // [s] since opening
  int id;
  double mass, vx, vy;
  bool keystone;     // removed by hand (note 4), not through the outlet
};

struct DischargeResult {
  std::string status;      // "discharged" (end time), "jammed", "emptied", "unstable", "interrupted"
  std::string reason;      // unstable: what grew where
  double t_open = 0;       // [s] world time at opening
  double duration = 0;     // [s] simulated since opening
  double wall_seconds = 0; // [s] of computing
  int n_initial = 0;
  std::vector<Removal> removals;
  double jam_at = -1;      // [s] since opening when a jam was declared (first one), -1 none
  int jams = 0;            // jams met (each resolved by a keystone removal, or the last one stopped the run)
  nlohmann::ordered_json metrics;  // flow rate, ratios, pattern (docs/outputs.md)
};

// Opens the gate and runs the discharge phase, writing series and snapshots into out_dir
// (which exists). The world must be at the state to open from. The last good state is kept in
// `good` every kKeepEvery steps (last_good.hpp) when given.
DischargeResult run_discharge(const SceneSpec& spec, World& w, const std::string& out_dir, bool progress,
                              LastGood* good = nullptr);

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
  double overlap_limit = 0;  // [cm] end.max_overlap x r_min at opening
  double rmean = 0;          // [cm] mean radius at opening (surface sinking)
  double fill_top = -1e300;
  double surf0[3] = {0, 0, 0};  // surface of the wall, centre and wall columns
  OpeningPositions at_open;     // positions at opening, by disc id (a file beside the outputs)
  std::vector<WallLoad> static_walls;
  // Running.
  long next_s = 0;           // next loop step (steps since opening)
  std::string status = "discharged";
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
  std::ostringstream totals, flow, pvd_d, pvd_c;  // the text of the other series files and .pvd entries
  std::vector<std::vector<PeakTracker>> bin_peaks;  // per wall and bin: peaks of the normal force
  std::vector<PeakTracker> total_peaks;             // per wall: peaks of the total normal force
  std::vector<double> sample_t;
  std::size_t next_snap = 0;
  double last_removal = 0, removed_mass = 0, moved_fraction = 0;
  double wall_seconds = 0;   // [s] of computing in earlier sessions (before the last checkpoint)
  EnergyWatch energy;        // budget from the opening (blowup.hpp)

  void save(BinaryOut& o) const;
  void load(BinaryIn& r);  // an "interrupted" status is read as going on
};

// Records the state at opening and removes the gate; returns "" or why it cannot open.
std::string open_discharge(const SceneSpec& spec, World& w, DischargeState& st);
// Why a discharge resumed from a checkpoint cannot go on with its wall series file ("" : it can).
std::string series_file_problem(const std::string& out_dir, const DischargeState& st);
// Runs the discharge from st (just opened, or restored from a checkpoint with the world) to its
// end, a jam, or a stop request (status "interrupted"), then writes its files and metrics.
DischargeResult continue_discharge(const SceneSpec& spec, World& w, DischargeState& st, const std::string& out_dir,
                                   bool progress, const RunControl* ctl, LastGood* good = nullptr);

// What one find_arch call searched: the searches run (each in a wider disc around the slit than
// the last, the last over all records) and the records they read, summed.
struct ArchStats {
  int searches = 0;
  std::size_t records = 0;
};

// Disc indices of the arch over the slit: the shortest chain of touching discs from one slit end
// (point L or the bottom wall within 2 r of it) to the other, over the pairs with a compressive
// total force in this step's recorded pass. Empty when there is none.
std::vector<int> find_arch(const World& w, double slit_left, double slit_right, double floor_y,
                           ArchStats* stats = nullptr);

// Least-squares slope of cumulative removed mass against time, after the start transient
// (from the 5th removal on); NaN with fewer than 10 removals.
double flow_rate(const std::vector<Removal>& removals);

}  // namespace dem
