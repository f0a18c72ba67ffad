// One contact's frame (4), its increments over the last step (5) and its force on the discs (15),
// written once for every kind of contact: disc pairs, discs on walls and points (fixed or
// moving: j is the obstacle) and paper 2's bonds. The law between them is contact_law.hpp.
#pragma once

namespace dem {

// (4): cos(alpha), sin(alpha), the unit vector from i to j.
struct UnitNormal {
  double x, y;
};
inline UnitNormal unit_normal(double dx, double dy, double R) { return {dx / R, dy / R}; }

// (5a): du_n from the relative displacement (ddx, ddy) = (du_i - du_j, dv_i - dv_j).
inline double normal_increment(double ddx, double ddy, UnitNormal n) { return ddx * n.x + ddy * n.y; }
// (5b): du_s, with the rotation term of i (r_i dphi_i) and of j (r_j dphi_j; none for a wall).
inline double shear_increment(double ddx, double ddy, UnitNormal n, double rot_i) {
  return -ddx * n.y + ddy * n.x + rot_i;
}
inline double shear_increment(double ddx, double ddy, UnitNormal n, double rot_i, double rot_j) {
  return shear_increment(ddx, ddy, n, rot_i) + rot_j;
}

// (15a), (15b): the force of one contact on disc i, the terms of X_i and Y_i (on j: its opposite).
// SHEAR = false: f_s is 0 and its terms are left out (the same sums).
struct ContactForce {
  double x, y;
};
template <bool SHEAR = true>
inline ContactForce contact_force(double fn, double fs, UnitNormal n) {
  ContactForce f{-fn * n.x, -fn * n.y};
  if constexpr (SHEAR) {
    f.x += fs * n.y;
    f.y -= fs * n.x;
  }
  return f;
}
// (15c): the term of M_i is -arm f_s; this is arm f_s, to subtract (the arm: r_i, or the lever
// arm of LeverArm::contact_point; for j its own arm, f_s being the same seen from j).
inline double contact_moment(double arm, double fs) { return arm * fs; }

}  // namespace dem
