// Run outputs (docs/outputs.md): summary.json, CSV profiles and contacts, VTU snapshots.
// Every file is written to NAME.tmp and renamed when complete.
#pragma once

#include <functional>
#include <ostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run/run.hpp"
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

// Writes all files of one run into dir (which must exist). `extra` is moved into summary.json
// (left empty): its series are some MB at a million discs, not copied at the run's last peak.
void write_outputs(const std::string& dir, const SceneSpec& spec, const World& w, const RunResult& res,
                   const StabilityReport& stab, nlohmann::ordered_json* extra = nullptr);

// STEM.csv and STEM.vtu of the touching contacts (docs/outputs.md).
void write_contact_files(const std::string& dir, const std::string& stem, const World& w);
// STEM.csv and STEM.vtu of the discs; with displacement columns from the positions at opening
// when given.
void write_disc_files(const std::string& dir, const std::string& stem, const SceneSpec& spec, const Discs& d,
                      const OpeningPositions* at_open);

// A double at full precision (%.17g), and a JSON number or null when not finite.
std::string fmt17(double v);
nlohmann::ordered_json finite_or_null(double v);

// Atomic text file write: path.tmp then rename.
void write_file_atomic(const std::string& path, const std::string& text);
// The same, streaming: `write` fills PATH.tmp, renamed to PATH when complete.
void write_stream_atomic(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace dem
