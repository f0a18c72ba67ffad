// Contact-law options and per-pair constants. The paper's behaviour is every default;
// each alternative is a named deviation used to match LIGGGHTS or YADE (docs/scene.md).
#pragma once

#include <string>

namespace dem {

// Normal elastic force.
enum class NormalSpring {
  incremental,  // paper eq. (7a): e_n += K_n du_n, started at 0 when the contact forms
  overlap       // e_n = K_n * overlap (LIGGGHTS hooke, YADE ViscEl)
};

// Where the no-tension rule acts.
enum class NoTension {
  elastic,  // paper eqs. (8), (12): if e_n < 0 then e_n = d_n = e_s = d_s = 0
  total,    // f_n = max(0, e_n + d_n) (YADE, LIGGGHTS limitForce on)
  overlap,  // no clamp; the contact ends only when the overlap vanishes (LIGGGHTS limitForce off)
  none      // paper 2's cluster bonds: tension carried, no rule at all (no scene option)
};

// What the Coulomb cap of eq. (13) is measured against.
enum class FrictionCap {
  elastic,  // paper eq. (13): |e_s| <= mu e_n
  total,    // |e_s| <= mu |f_n| (LIGGGHTS, YADE)
  none      // paper 2's cluster bonds: no cap (no scene option)
};

// The lever arm of a contact: the distance from a disc's centre at which the shear force acts
// (torque, eq. 15c) and at which the disc's rotation moves the contact (the r dphi of eq. 5b).
enum class LeverArm {
  radius,        // paper eqs. (5b), (15c): r_i
  contact_point  // r_i - overlap/2: the middle of the overlap (LIGGGHTS' contact radius, YADE's contact point)
};

// Time integration, chosen per scene.
enum class Scheme {
  paper_eq18,      // eqs. (17)-(18): v += a dt; du = v dt (symplectic Euler)
  paper_eq19,      // eqs. (17), (19): du = (du_prev + v dt) / 2
  velocity_verlet,  // half kick, drift, force, half kick; dashpots see du/dt = v(t + dt/2)
  // Velocity Verlet made second order in a collision (onset.cpp): the dashpots see the predicted
  // v(t + dt), the impulse a contact or a slip starting inside the step misses is added. Needs
  // the overlap spring; no bonds, no moving walls; its force pass runs on one thread.
  velocity_verlet_onset
};

// Schemes of the velocity Verlet family: half kick, drift, forces, half kick (no stored increments).
constexpr bool verlet_family(Scheme s) { return s == Scheme::velocity_verlet || s == Scheme::velocity_verlet_onset; }

struct ContactOptions {
  NormalSpring normal_spring = NormalSpring::incremental;
  NoTension no_tension = NoTension::elastic;
  FrictionCap friction_cap = FrictionCap::elastic;
  LeverArm lever_arm = LeverArm::radius;
};

// Constants of one material pair, per unit thickness (cgs: dyn/cm per cm, g/s per cm).
struct PairProps {
  double kn = 0;     // K_n normal spring
  double ks = 0;     // K_s shear spring
  double eta_n = 0;  // normal dashpot
  double eta_s = 0;  // shear dashpot
  double mu = 0;     // Coulomb friction coefficient, eq. (13)
};

const char* to_string(NormalSpring v);
const char* to_string(NoTension v);
const char* to_string(FrictionCap v);
const char* to_string(LeverArm v);
const char* to_string(Scheme v);

}  // namespace dem
