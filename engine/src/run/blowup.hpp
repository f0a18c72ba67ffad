// Blow-up detection by energy: without a source (moving walls are one), the mechanical energy
// kinetic + gravitational can only fall below its start value plus the elastic energy stored
// then. A run whose kinetic + potential energy rises above that by more than `gain` x the energy
// scale is creating energy: a numerical instability. Checked every few steps; the message says
// what grew and where (the fastest disc).
#pragma once

#include <string>

#include "scene/units.hpp"

namespace dem {

class World;

struct EnergyWatch {
  double budget = 0;  // [erg per cm] KE + PE + elastic energy at the start
  double scale = 0;   // [erg per cm] KE + elastic at start + M g (height span + 2 r_max)
  double gain = 0.05; // end.max_energy_gain: allowed excess as a fraction of `scale`
  bool active = false;

  // Records the start (call after the forces of the start are known).
  void start(const World& w, double max_gain);
  // "" while the energy stays within budget; else what grew, by how much, and where (in the
  // scene's units: their names are looked up only for that message).
  std::string check(const World& w, Units units) const;
};

// Gravitational potential energy -sum m (g . x), elastic energy of the contact springs
// (e_n^2 / 2 K_n + e_s^2 / 2 K_s), kinetic energy of translation and rotation.
double potential_energy(const World& w);
double elastic_energy(const World& w);

}  // namespace dem
