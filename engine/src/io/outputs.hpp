// Run outputs (docs/outputs.md): summary.json, CSV profiles and contacts, VTU snapshots.
// Every file is written to NAME.tmp and renamed when complete.
#pragma once

#include <functional>
#include <ostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/files.hpp"
#include "scene/scene.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"

namespace dem {
class OpeningPositions;
}

namespace dem {

// Forces exerted by the discs on one wall, totals and per bin along the wall.
struct WallLoad {
  std::string name, group;
  double fx = 0, fy = 0;           // resultant on the wall
  double normal = 0, shear = 0;    // along the inward normal reversed / along from -> to
  int contacts = 0;
  std::vector<double> bin_normal, bin_shear;
  std::vector<int> bin_contacts;
  double bin = 0, length = 0;
};
struct PointLoad {
  std::string name, group;
  double x = 0, y = 0, fx = 0, fy = 0;
  int contacts = 0;
};

void measure_loads(const World& w, double bin, std::vector<WallLoad>& walls, std::vector<PointLoad>& points);

// What summary.json says about the run beside the world (run/scene_run.hpp fills it).
struct RunSummary {
  std::string status;          // run/status.hpp's word
  std::string reason;          // why an unstable run stopped
  bool unstable = false;
  bool rest_reached = false;   // the fill's rest measure (run/fill_phase.hpp)
  double rest_time = 0, rest_threshold = 0, mean_abs_du = 0, mean_abs_dv = 0;
  double wall_seconds = 0;     // [s] of stepping
  const Discs* good = nullptr; // an unstable run writes these (its last good state) in place of the world's discs
  std::vector<std::string> command;  // the command line (argv), for summary.json
};

// The time-step bounds as summary.json's "stability" (and `dem resolve --stability`) give them.
nlohmann::ordered_json stability_json(const StabilityReport& stab, Units units);

// Writes all files of one run into dir (which must exist). `extra` is moved into summary.json
// (left empty): its series are some MB at a million discs, not copied at the run's last peak.
void write_outputs(const std::string& dir, const SceneSpec& spec, const World& w, const RunSummary& res,
                   const StabilityReport& stab, nlohmann::ordered_json* extra = nullptr);

// STEM.csv and STEM.vtu of the touching contacts (docs/outputs.md); STEM.vtu only with `vtu`
// (SceneSpec::vtu_files). `binary`: the VTU file binary (SceneSpec::vtu_binary), else ASCII.
void write_contact_files(const std::string& dir, const std::string& stem, const World& w, bool binary, bool vtu);
// STEM.csv and STEM.vtu of the discs (STEM.vtu unless output.vtu = "none"); with displacement
// columns from the positions at opening when given. The VTU carries each disc's velocity, force,
// omega, torque, radius, id and material, and, when `world` holds d, its number of contacts.
void write_disc_files(const std::string& dir, const std::string& stem, const SceneSpec& spec, const Discs& d,
                      const OpeningPositions* at_open, const World* world = nullptr);


}  // namespace dem
