// The discs' forces on the obstacles: each wall's totals and profile in bins along it, each
// point's resultant (summary.json's walls and points, a discharge's wall series).
#pragma once

#include <string>
#include <vector>

namespace dem {

class World;

// Forces exerted by the discs on one wall, totals and per bin along the wall.
struct WallLoad {
  std::string name, group;
  double fx = 0, fy = 0;           // resultant on the wall
  double normal = 0, shear = 0;    // along the inward normal reversed / along from -> to
  int contacts = 0;
  std::vector<double> bin_normal, bin_shear;
  std::vector<int> bin_contacts;
  double bin = 0, length = 0;
};
struct PointLoad {
  std::string name, group;
  double x = 0, y = 0, fx = 0, fy = 0;
  int contacts = 0;
};

// The loads of every wall (geometry order) and point, over the touching obstacle contacts.
struct Loads {
  std::vector<WallLoad> walls;
  std::vector<PointLoad> points;
};

// `bin`: the profile's bin length along each wall (output.profile_bin).
void measure_loads(const World& w, double bin, std::vector<WallLoad>& walls, std::vector<PointLoad>& points);
Loads measure_loads(const World& w, double bin);

}  // namespace dem
