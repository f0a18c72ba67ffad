#include "measures/wall_loads.hpp"

#include <algorithm>
#include <cmath>

#include "physics/world.hpp"

namespace dem {

void measure_loads(const World& w, double bin, std::vector<WallLoad>& walls, std::vector<PointLoad>& points) {
  const Geometry& g = w.geometry;
  const int nw = static_cast<int>(g.walls.size());
  walls.clear();
  points.clear();
  for (const Wall& wl : g.walls) {
    WallLoad L;
    L.name = wl.name;
    L.group = wl.group;
    L.bin = bin;
    L.length = std::hypot(wl.bx - wl.ax, wl.by - wl.ay);
    const std::size_t nb = static_cast<std::size_t>(std::ceil(L.length / bin - 1e-9));
    L.bin_normal.assign(nb, 0);
    L.bin_shear.assign(nb, 0);
    L.bin_contacts.assign(nb, 0);
    walls.push_back(L);
  }
  for (const Point& p : g.points) points.push_back({p.name, p.group, p.x, p.y});
  for (const WallContact& c : w.neighbors.walls) {
    if (!c.touching) continue;
    // Force on the obstacle: f_n n + f_s t, t = (-n_y, n_x) (the opposite of eq. 15 on the disc).
    const double fx = c.fn * c.nx - c.fs * c.ny, fy = c.fn * c.ny + c.fs * c.nx;
    if (c.k < nw) {
      const Wall& wl = g.walls[c.k];
      WallLoad& L = walls[c.k];
      const double ex = (wl.bx - wl.ax) / L.length, ey = (wl.by - wl.ay) / L.length;
      const double shear = fx * ex + fy * ey;
      L.fx += fx; L.fy += fy;
      L.normal += c.fn;
      L.shear += shear;
      ++L.contacts;
      const double s = (c.px - wl.ax) * ex + (c.py - wl.ay) * ey;
      std::size_t b = static_cast<std::size_t>(std::max(0.0, std::floor(s / bin)));
      b = std::min(b, L.bin_normal.size() - 1);
      L.bin_normal[b] += c.fn;
      L.bin_shear[b] += shear;
      ++L.bin_contacts[b];
    } else {
      PointLoad& P = points[c.k - nw];
      P.fx += fx; P.fy += fy;
      ++P.contacts;
    }
  }
}

Loads measure_loads(const World& w, double bin) {
  Loads l;
  measure_loads(w, bin, l.walls, l.points);
  return l;
}

}  // namespace dem
