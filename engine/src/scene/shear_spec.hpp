// The simple shear box of paper 2 as the scene gives it ([shear_box], [shear]; docs/scene.md).
#pragma once

#include <vector>

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

}  // namespace dem
