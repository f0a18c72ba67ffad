// Initial disc arrangements: the paper's (s-1)/s lattices and explicit lists.
#pragma once

#include <string>
#include <vector>

namespace dem {

struct LatticeSpec {
  int s = 18;            // discs in the bottom row; rows alternate s, s-1 ("(s-1)/s arrangement")
  double radius = 1.0;   // [cm]
  double gap = 0.004;    // [cm] initial gap to diagonal neighbours and to the side walls
  long rows = 0;         // 0: choose rows so that the count is closest to `count`
  long count = 350;      // target number of discs
};

struct LatticeGeometry {
  double pitch;      // horizontal spacing in a row [cm]
  double row_height; // vertical spacing of rows [cm]
  long rows;
  long n;            // number of discs
};

// Row pitch p = (W - 2r - 2 gap)/(s-1) puts the bottom row's end discs one gap from the walls;
// rows are h = sqrt((2r + gap)^2 - (p/2)^2) apart so diagonal neighbours are one gap apart.
// Returns an empty string when valid, else the reason.
std::string lattice_geometry(const LatticeSpec& L, double width, LatticeGeometry& out);

// Centres (x, y) of the lattice in a box [x0, x0 + width] with floor at y0.
void lattice_centres(const LatticeSpec& L, const LatticeGeometry& g, double x0, double y0,
                     std::vector<double>& x, std::vector<double>& y);

}  // namespace dem
