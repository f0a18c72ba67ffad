// A discharge's flow: the discs that left and the rate they left at, and the heights of the
// free surface over the silo's walls and centre.
#pragma once

#include <vector>

namespace dem {

struct Discs;

// A disc leaving the silo.
struct Removal {
  double t;          // [s] since opening
  int id;
  double mass, vx, vy;
  bool keystone;     // removed by hand (note 4), not through the outlet
};

// Least-squares slope of cumulative removed mass against time, after the start transient
// (from the 5th removal on); NaN with fewer than 10 removals.
double flow_rate(const std::vector<Removal>& removals);

// Top of the fill (the highest disc top among discs above `floor`) in the left wall column
// [x_left, x_left + col), the centre column of width col around xc and the right wall column.
void surfaces(const Discs& d, double x_left, double xc, double x_right, double floor, double col, double s[3]);

}  // namespace dem
