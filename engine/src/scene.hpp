// Scene files (TOML, docs/scene.md): reading, validation, and building a World.
// Everything is checked before any step; errors name the file, the field, the value, the reason.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "geometry.hpp"
#include "model.hpp"

namespace dem {

class World;

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct DiscInit {
  double x, y, r;
  int material;
};

struct SceneSpec {
  std::string file, name, description;
  double gx = 0, gy = -980.0;      // [physics] gravity [cm/s^2]
  Scheme scheme = Scheme::paper_eq19;
  double dt = 0;                   // [s]
  bool force_dt = false;
  ContactOptions contact;
  std::vector<std::string> material_names;
  std::vector<double> density;     // [g/cm^3]; 0 for obstacle-only materials
  std::vector<PairProps> props;    // n x n
  std::vector<char> props_set;
  Geometry geometry;
  bool has_silo = false;
  double silo_width = 0, silo_height = 0, slit_width = 0;
  bool slit_open = false;
  std::vector<DiscInit> discs;
  std::string fill_summary;
  double skin = 0, cell = 0;       // [neighbor]
  double end_time = 0;             // [end]
  bool stop_at_rest = true;
  double rest_factor = 1e-4;
  double max_overlap_fraction = 0.5;
  double profile_bin = 0;          // [output]
  bool progress = true;
};

// Reads and validates; throws SceneError. Overrides (NaN / empty = none) come from the CLI.
struct SceneOverrides {
  double dt = 0;              // 0: none
  std::string scheme;         // "": none
  double end_time = 0;        // 0: none
  bool force_dt = false;
};
SceneSpec load_scene(const std::string& path, const SceneOverrides& ov = {});

// Builds the world; throws SceneError for a dt above the scheme's bound (unless forced).
void build_world(const SceneSpec& s, World& w);

Scheme parse_scheme(const std::string& s, bool& ok);

}  // namespace dem
