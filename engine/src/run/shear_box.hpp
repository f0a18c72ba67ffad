// The simple shear test of paper 2 (Sumita, Kiyama & Nishimura): a box b wide, the discs in a
// regular arrangement (with or without clusters), a rigid top plate with its own weight that
// moves vertically and horizontally but does not rotate; after compression under the plate the
// left and right walls stay parallel and turn about their lower ends at a constant rate.
// Stresses on virtual horizontal planes (stress_planes.hpp) against the shear strain.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run/last_good.hpp"

namespace dem {

struct ShearBoxSpec {
  bool enabled = false;
  double width = 40.0;          // b [cm]
  double height = 20.0;         // h [cm], nominal height of the sample
  double wall_length = 0;       // side walls from their lower ends [cm]; 0: 1.5 h
  int wall_material = -1;       // side walls and floor
  int plate_material = -1;
  double plate_volume = 1500.0; // F/(rho g) [cm^3 per cm of thickness]
  double plate_density = 0;     // [g/cm^3]; 0: the fill material's
  double plate_gap = 0.004;     // [cm] initial gap above the highest disc
  double plate_overhang = 4.0;  // [cm] the plate reaches this far beyond each side wall
  bool plate_follows_walls = false;  // true: horizontal motion with the walls; false: free
  double plate_y = 0;           // [cm] plate height (set after the fill)
  double plate_mass = 0;        // [g per cm] (set after the fill)
  // [shear]
  bool shear = false;
  double rate = 0.05;           // [rad/s] the side walls' rotation rate (tops move to +X)
  double max_strain = 0.15;     // gamma = tan(angle of the walls)
  double sample_strain = 0.001;
  std::vector<double> snapshots = {0.0, 0.05};  // strains
};

class World;
struct SceneSpec;

struct ShearResult {
  std::string status;       // "sheared" or "unstable"
  std::string reason;
  double wall_seconds = 0;
  nlohmann::ordered_json metrics;  // docs/outputs.md, "Shear outputs"
};

// The box's walls, plate and bonds in a world built from the scene (called by build_world).
void build_shear_world(const SceneSpec& s, World& w);

// Shears the compressed sample to max_strain, writing shear_series.csv, shear_planes.csv and
// snapshots into out_dir (which exists). The last good state is kept in `good` every kKeepEvery
// steps (last_good.hpp) when given.
ShearResult run_shear(const SceneSpec& spec, World& w, const std::string& out_dir, bool progress,
                      LastGood* good = nullptr);

}  // namespace dem
