// Moving obstacles: walls rotating about a pivot at a prescribed rate (the shear box's side
// walls), rigid plates with their own weight (its top plate), integrated with the discs'
// scheme, and walls translating at a prescribed velocity during a time window (a scene's
// walls[].velocity: a floor lowered under a column). A wall's motion over the last step enters
// the contact increments (5a), (5b) through the displacement of the wall's material point at the
// contact. The kernel list has a feature for moving walls (kernels.hpp): a scene whose walls
// stay put runs a kernel without it.
#pragma once

#include <algorithm>
#include <vector>

namespace dem {

// Last step's rigid displacement of one obstacle: a point p of it moved by
// (dux, duy) + dtheta * e_z x (p - pivot). And the force the discs exert on it in the last force
// computation, with its moment about the pivot (counter-clockwise positive).
struct ObstacleMotion {
  double dux = 0, duy = 0, dtheta = 0;
  double pivot_x = 0, pivot_y = 0;
  double fx = 0, fy = 0, moment = 0;
};

// A wall turning about a fixed pivot; theta counter-clockwise from its scene position.
struct RotatingWall {
  int wall = 0;                         // index into Geometry::walls
  double pivot_x = 0, pivot_y = 0;
  double ax0 = 0, ay0 = 0, bx0 = 0, by0 = 0;  // endpoints at theta = 0
  double theta = 0;                     // [rad]
  double omega = 0;                     // [rad/s] prescribed
  double reach = 0;                     // farthest endpoint from the pivot [cm]
  double theta_listed = 0;              // theta at the last neighbour-list build
};

// A straight plate translating as a rigid body (no rotation) under gravity and the discs' forces.
// With follow >= 0 its horizontal motion is prescribed instead: it keeps the horizontal offset
// of the rotating wall `follow` at the plate's height (the plate moves with the side walls).
struct RigidPlate {
  int wall = 0;
  double mass = 0;                      // [g per cm of thickness]
  double ax0 = 0, ay0 = 0, bx0 = 0, by0 = 0;  // endpoints at zero displacement
  double x = 0, y = 0;                  // displacement [cm]
  double vx = 0, vy = 0;
  double dux = 0, duy = 0;              // last step's increments, (18) or (19)
  int follow = -1;                      // index into MovingWalls::rotating, or -1: free
  double x_free = 0;                    // follow: horizontal displacement at theta = 0
  double x_listed = 0, y_listed = 0;    // displacement at the last neighbour-list build
};

// A wall translating at a prescribed velocity (vx, vy) while t_from <= t <= t_until: at time t
// it is displaced by (vx, vy) x clamp(t - t_from, 0, t_until - t_from) from its scene position,
// so a step covering part of the window moves it by that part only.
struct TranslatingWall {
  int wall = 0;
  double vx = 0, vy = 0;                // [cm/s]
  double t_from = 0, t_until = 0;       // [s]
  double ax0 = 0, ay0 = 0, bx0 = 0, by0 = 0;  // endpoints at zero displacement (the scene's)
  double x = 0, y = 0;                  // displacement [cm]
  double x_listed = 0, y_listed = 0;    // displacement at the last neighbour-list build
  double moved(double t) const { return std::clamp(t - t_from, 0.0, t_until - t_from); }  // [s] of motion by t
};

struct MovingWalls {
  std::vector<ObstacleMotion> motion;   // one per obstacle (walls, then points); empty: nothing moves
  std::vector<RotatingWall> rotating;
  std::vector<RigidPlate> plates;
  std::vector<TranslatingWall> translating;
  bool empty() const { return rotating.empty() && plates.empty() && translating.empty(); }
  // The time after which no prescribed translation moves a wall (0 without any).
  double translations_end() const {
    double t = 0;
    for (const TranslatingWall& q : translating) t = q.t_until > t ? q.t_until : t;
    return t;
  }
};

}  // namespace dem
