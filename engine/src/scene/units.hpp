// The unit system of a scene (physics.units, docs/scene.md): the defaults that carry a unit and
// the unit names printed in headers and messages. The engine computes in whatever consistent
// units the numbers are given in; only defaults and words depend on the system.
#pragma once

namespace dem {

enum class Units { cgs, si };

struct UnitNames {
  const char* length;        // cm | m
  const char* velocity;      // cm/s | m/s
  const char* acceleration;  // cm/s^2 | m/s^2
  const char* density;       // g/cm^3 | kg/m^3
  const char* mass;          // g per cm of thickness | kg per m of thickness
  const char* force;         // dyn/cm | N/m: forces per unit thickness
  const char* energy;        // erg/cm | J/m: energies per unit thickness
  const char* stiffness;     // g/s^2 per cm | kg/s^2 per m
};

inline const char* to_string(Units u) { return u == Units::si ? "si" : "cgs"; }

inline UnitNames unit_names(Units u) {
  if (u == Units::si) return {"m", "m/s", "m/s^2", "kg/m^3", "kg/m", "N/m", "J/m", "kg/s^2 per m"};
  return {"cm", "cm/s", "cm/s^2", "g/cm^3", "g/cm", "dyn/cm", "erg/cm", "g/s^2 per cm"};
}

// A default length given in cm (the paper's scenes), in the scene's system.
inline double default_length(Units u, double cm) { return u == Units::si ? cm * 0.01 : cm; }
// A default area per unit thickness given in cm^2 (a plate's F/(rho g)).
inline double default_area(Units u, double cm2) { return u == Units::si ? cm2 * 1e-4 : cm2; }
// Gravity along -Y: the paper's 980 cm/s^2, or 9.81 m/s^2.
inline double default_gravity_y(Units u) { return u == Units::si ? -9.81 : -980.0; }

}  // namespace dem
