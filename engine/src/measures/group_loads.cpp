#include "measures/group_loads.hpp"

#include <algorithm>
#include <cmath>

#include "physics/world.hpp"

namespace dem {

GroupLoads measure_group_loads(const World& w, const std::vector<std::string>& groups) {
  GroupLoads l;
  for (const PairContact& c : w.neighbors.pairs) l.contacts += c.en > 0;
  l.normal.assign(groups.size(), 0.0);
  l.shear.assign(groups.size(), 0.0);
  const int nw = static_cast<int>(w.geometry.walls.size());
  for (const WallContact& c : w.neighbors.walls) {
    if (!c.touching) continue;
    ++l.wall_contacts;
    if (c.k >= nw) continue;  // a point: in no wall group
    const Wall& wl = w.geometry.walls[c.k];
    // The discs' force on the wall (as measure_loads): normal f_n, shear along from -> to.
    const double fx = c.fn * c.nx - c.fs * c.ny, fy = c.fn * c.ny + c.fs * c.nx;
    const double len = std::hypot(wl.bx - wl.ax, wl.by - wl.ay);
    const std::size_t g = static_cast<std::size_t>(std::find(groups.begin(), groups.end(), wl.group) - groups.begin());
    if (g == groups.size() || !(len > 0)) continue;
    l.normal[g] += c.fn;
    l.shear[g] += (fx * (wl.bx - wl.ax) + fy * (wl.by - wl.ay)) / len;
  }
  return l;
}

}  // namespace dem
