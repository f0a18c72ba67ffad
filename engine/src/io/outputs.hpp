// Run outputs (docs/outputs.md): summary.json, CSV profiles and contacts, VTU snapshots.
// Every file is written to NAME.tmp and renamed when complete.
#pragma once

#include <functional>
#include <ostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/files.hpp"
#include "measures/wall_loads.hpp"
#include "scene/scene.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"

namespace dem {
class OpeningPositions;
}

namespace dem {

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

// Writes all files of one run into dir (which must exist). `loads`: the world's loads on the
// walls and points (measure_loads with spec.profile_bin). `extra` is moved into summary.json
// (left empty): its series are some MB at a million discs, not copied at the run's last peak.
void write_outputs(const std::string& dir, const SceneSpec& spec, const World& w, const Loads& loads,
                   const RunSummary& res, const StabilityReport& stab, nlohmann::ordered_json* extra = nullptr);

// STEM.csv and STEM.vtu of the touching contacts (docs/outputs.md); STEM.vtu only with `vtu`
// (SceneSpec::vtu_files). `binary`: the VTU file binary (SceneSpec::vtu_binary), else ASCII.
void write_contact_files(const std::string& dir, const std::string& stem, const World& w, bool binary, bool vtu);
// STEM.csv and STEM.vtu of the discs (STEM.vtu unless output.vtu = "none"); with displacement
// columns from the positions at opening when given. The VTU carries each disc's velocity, force,
// omega, torque, radius, id and material, and, when `world` holds d, its number of contacts.
void write_disc_files(const std::string& dir, const std::string& stem, const SceneSpec& spec, const Discs& d,
                      const OpeningPositions* at_open, const World* world = nullptr);


}  // namespace dem
