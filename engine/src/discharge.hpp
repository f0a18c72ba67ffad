// Section 5(2) of the silo paper: the slit opens under the rested fill; discs fall through,
// are followed below it, and leave the computation at the outlet depth. Records what the paper
// drew (wall forces, flow pictures) and what it could not (series, ratios, jams, patterns).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene.hpp"
#include "world.hpp"

namespace dem {

struct Removal {
  double t;          // [s] since opening
  int id;
  double mass, vx, vy;
  bool keystone;     // removed by hand (note 4), not through the outlet
};

struct DischargeResult {
  std::string status;      // "discharged" (end time), "jammed", "emptied", "unstable"
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
// (which exists). The world must be at the state to open from.
DischargeResult run_discharge(const SceneSpec& spec, World& w, const std::string& out_dir, bool progress);

// Disc ids of the arch over the slit: the shortest chain of touching discs from one slit end
// (point L or the bottom wall within 2 r of it) to the other. Empty when there is none.
std::vector<int> find_arch(const World& w, double slit_left, double slit_right, double floor_y);

// Least-squares slope of cumulative removed mass against time, after the start transient
// (from the 5th removal on); NaN with fewer than 10 removals.
double flow_rate(const std::vector<Removal>& removals);

}  // namespace dem
