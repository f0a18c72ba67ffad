// Fixed obstacles: straight wall segments (plane contacts) and points (contacts from any
// direction, the paper's slit ends L and R).
#pragma once

#include <string>
#include <vector>

namespace dem {

struct Wall {
  std::string name;
  std::string group;  // force reporting group, e.g. "side_left", "bottom"
  double ax, ay, bx, by;  // from (a) -> to (b); shear on the wall is reported along a -> b
  int material;
  bool active = true;     // false once removed (the slit's gate after opening)
  // A prescribed translation (walls[].velocity, move_from, move_until): the wall moves by
  // (move_vx, move_vy) per second while move_from <= t <= move_until, else stays put.
  double move_vx = 0, move_vy = 0, move_from = 0, move_until = 0;
  bool moves() const { return (move_vx != 0 || move_vy != 0) && move_until > move_from; }
};

struct Point {
  std::string name;
  std::string group;
  double x, y;
  int material;
  std::vector<int> adjacent;  // walls ending here: the point acts only where they do not
};

struct Geometry {
  std::vector<Wall> walls;
  std::vector<Point> points;
  // Links each point to the walls that end at it (within tol).
  void link_points(double tol = 1e-9);
  int obstacle_count() const { return static_cast<int>(walls.size() + points.size()); }
  // Bounding box of all walls and points.
  double min_x() const;
  double max_x() const;
  double min_y() const;
  double max_y() const;
};

// Closest-point data of a disc centre (cx, cy) against obstacle k (walls first, then points).
// Returns false when the obstacle cannot touch from there: a wall only acts where the centre
// projects inside it (plane contact); a point only where no adjacent wall does.
struct ObstacleHit {
  double px, py;  // closest point on the obstacle
  double dist;    // distance centre -> closest point
};
bool closest_point(const Geometry& g, int k, double cx, double cy, ObstacleHit& hit);

// Distance from (cx, cy) to any part of obstacle k, ends included, whoever owns the contact
// (infinite for a removed wall): for candidate lists and initial-overlap checks.
double obstacle_distance(const Geometry& g, int k, double cx, double cy);

}  // namespace dem
