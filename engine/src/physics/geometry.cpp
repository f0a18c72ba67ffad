#include "physics/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dem {

void Geometry::link_points(double tol) {
  for (auto& p : points) {
    p.adjacent.clear();
    for (int w = 0; w < static_cast<int>(walls.size()); ++w) {
      const Wall& s = walls[w];
      if (!s.active) continue;
      if (std::hypot(s.ax - p.x, s.ay - p.y) <= tol || std::hypot(s.bx - p.x, s.by - p.y) <= tol)
        p.adjacent.push_back(w);
    }
  }
}

namespace {
template <class F>
double extreme(const Geometry& g, F pick, bool want_max) {
  double v = want_max ? -std::numeric_limits<double>::infinity()
                      : std::numeric_limits<double>::infinity();
  auto take = [&](double c) { v = want_max ? std::max(v, c) : std::min(v, c); };
  for (const auto& w : g.walls) { take(pick(w.ax, w.ay)); take(pick(w.bx, w.by)); }
  for (const auto& p : g.points) take(pick(p.x, p.y));
  return v;
}
double px_(double x, double) { return x; }
double py_(double, double y) { return y; }

// Projection parameter of c on segment ab (0 at a, 1 at b).
double projection(const Wall& w, double cx, double cy) {
  const double ex = w.bx - w.ax, ey = w.by - w.ay;
  return ((cx - w.ax) * ex + (cy - w.ay) * ey) / (ex * ex + ey * ey);
}
}  // namespace

double Geometry::min_x() const { return extreme(*this, px_, false); }
double Geometry::max_x() const { return extreme(*this, px_, true); }
double Geometry::min_y() const { return extreme(*this, py_, false); }
double Geometry::max_y() const { return extreme(*this, py_, true); }

bool closest_point(const Geometry& g, int k, double cx, double cy, ObstacleHit& hit) {
  const int nw = static_cast<int>(g.walls.size());
  if (k < nw) {
    const Wall& w = g.walls[k];
    if (!w.active) return false;
    const double u = projection(w, cx, cy);
    if (u < 0.0 || u > 1.0) return false;  // plane contact only
    hit.px = w.ax + u * (w.bx - w.ax);
    hit.py = w.ay + u * (w.by - w.ay);
  } else {
    const Point& p = g.points[k - nw];
    for (int a : p.adjacent) {
      const double u = projection(g.walls[a], cx, cy);
      if (u >= 0.0 && u <= 1.0) return false;  // the wall owns this contact
    }
    hit.px = p.x;
    hit.py = p.y;
  }
  hit.dist = std::hypot(hit.px - cx, hit.py - cy);
  return true;
}

double obstacle_distance(const Geometry& g, int k, double cx, double cy) {
  const int nw = static_cast<int>(g.walls.size());
  if (k >= nw) return std::hypot(g.points[k - nw].x - cx, g.points[k - nw].y - cy);
  const Wall& w = g.walls[k];
  if (!w.active) return std::numeric_limits<double>::infinity();
  const double u = std::clamp(projection(w, cx, cy), 0.0, 1.0);
  return std::hypot(w.ax + u * (w.bx - w.ax) - cx, w.ay + u * (w.by - w.ay) - cy);
}

}  // namespace dem
