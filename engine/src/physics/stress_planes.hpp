// Stresses of paper 2 on virtual horizontal shear planes: a plane runs through a chain of contacts
// (a horizontal line between two rows of discs); the x and y components of the forces of the
// contacts it cuts are summed and divided by the width b. sigma and tau of the assembly are the
// means over the planes.
#pragma once

#include <vector>

#include "physics/world.hpp"

namespace dem {

struct PlaneStress {
  double y = 0;        // height of the plane [cm]
  int contacts = 0;    // contacts (and bonds) cut by it
  double fx = 0, fy = 0;  // force exerted by the part above on the part below
  double sigma = 0;    // normal stress: -fy / b (compression positive)
  double tau = 0;      // shear stress: fx / b (positive when the part above drags the part below to +X)
  // The same from the quasi-static equilibrium of the part above (discs whose centre is above
  // y): its weight and the forces of the walls and the plate on it, a cross-check against the
  // plate and wall forces. The cut equals check + inertia exactly, inertia = sum(m a) / b of the
  // part above (vertical part with the sign of sigma, horizontal with the sign of tau).
  double sigma_check = 0, tau_check = 0;
  double sigma_inertia = 0, tau_inertia = 0;
};

// A contact (disc-disc pair or bond) is cut by the plane y = y0 when its centres lie on either
// side (y_i < y0 < y_j or the reverse). Forces are the totals with dashpots (f_n, f_s), with the
// directions and positions of the last force computation (eqs. 18/19 move the discs after it).
std::vector<PlaneStress> plane_stresses(const World& w, const std::vector<double>& plane_y, double width);

// Rows of a regular arrangement: discs sorted by height, a new row where consecutive heights
// differ by more than `gap` [cm]. Returns the row index of each disc and the number of rows.
std::vector<int> assign_rows(const Discs& d, double gap, int& n_rows);

// Plane heights between consecutive rows: the mean of the two rows' mean heights (current).
std::vector<double> planes_between_rows(const Discs& d, const std::vector<int>& row, int n_rows);

}  // namespace dem
