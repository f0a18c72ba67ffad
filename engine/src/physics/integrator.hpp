// The time integration (16)-(19), written once for the discs and the rigid plates of the shear
// box (moving_walls.hpp): a kick of the velocity, then the increment of the move and the drift.
#pragma once

namespace dem {

// What moves the bodies after a force pass (World::step lists it): nothing (a pass for its
// forces only), a kick alone (velocity Verlet's closing half), or a kick and the drift of (18)
// or (19).
enum class Move { none, kick, kick_drift_eq18, kick_drift_eq19 };

// (16), (17): v += a h, with a = X/m (h: dt, or dt/2 in velocity Verlet).
inline double kick(double v, double a, double h) { return v + a * h; }

// The increment of a move over dt from the new velocity v: (18) v dt, or (19) the mean of the
// last increment and v dt.
template <bool EQ19>
inline double move_increment(double du_last, double v, double dt) {
  if constexpr (EQ19) return 0.5 * (du_last + v * dt);  // (19)
  else return v * dt;                                   // (18)
}

}  // namespace dem
