// World's moving-wall stages (world.hpp): prescribed wall rotations, rigid plates and prescribed
// wall translations (their state: moving_walls.hpp), moved, placed and listed.
#include <algorithm>
#include <cmath>

#include "physics/integrator.hpp"
#include "physics/world.hpp"

namespace dem {

namespace {
void place_rotated(Wall& w, const RotatingWall& r) {
  const double c = std::cos(r.theta), s = std::sin(r.theta);
  auto turn = [&](double x, double y, double& ox, double& oy) {
    const double dx = x - r.pivot_x, dy = y - r.pivot_y;
    ox = r.pivot_x + c * dx - s * dy;
    oy = r.pivot_y + s * dx + c * dy;
  };
  turn(r.ax0, r.ay0, w.ax, w.ay);
  turn(r.bx0, r.by0, w.bx, w.by);
}

void place_plate(Wall& w, const RigidPlate& p) {
  w.ax = p.ax0 + p.x; w.ay = p.ay0 + p.y;
  w.bx = p.bx0 + p.x; w.by = p.by0 + p.y;
}

void place_translated(Wall& w, const TranslatingWall& q) {
  w.ax = q.ax0 + q.x; w.ay = q.ay0 + q.y;
  w.bx = q.bx0 + q.x; w.by = q.by0 + q.y;
}

// Horizontal displacement of a following plate: the rotating wall's offset at the plate's height.
double followed_x(const RigidPlate& p, const RotatingWall& r) {
  const double height = 0.5 * (p.ay0 + p.by0) + p.y - r.pivot_y;
  return p.x_free - height * std::tan(r.theta);
}
}  // namespace

// The plates move by the discs' integrator (integrator.hpp); the rotating walls turn at their
// prescribed rate, the exact turn of each step.
void World::move_walls(Move move, double h) {
  if (move == Move::none || moving.empty()) return;
  for (RigidPlate& p : moving.plates) {  // (16), (17); a plate does not rotate
    const ObstacleMotion& m = moving.motion[p.wall];
    // (16) as X / M, X the discs' forces plus M g: a plate's stored results have this rounding.
    if (p.follow < 0) p.vx = kick(p.vx, (m.fx + p.mass * gx) / p.mass, h);
    p.vy = kick(p.vy, (m.fy + p.mass * gy) / p.mass, h);
  }
  if (move == Move::kick) return;
  const bool eq19 = move == Move::kick_drift_eq19;
  for (RotatingWall& r : moving.rotating) {
    const double dtheta = r.omega * dt;
    r.theta += dtheta;
    place_rotated(geometry.walls[r.wall], r);
    ObstacleMotion& m = moving.motion[r.wall];
    m.dux = m.duy = 0;
    m.dtheta = dtheta;
    m.pivot_x = r.pivot_x;
    m.pivot_y = r.pivot_y;
  }
  for (RigidPlate& p : moving.plates) {
    p.duy = eq19 ? move_increment<true>(p.duy, p.vy, dt) : move_increment<false>(p.duy, p.vy, dt);  // (19), (18)
    p.y += p.duy;
    if (p.follow >= 0) {
      const double x = followed_x(p, moving.rotating[p.follow]);
      p.dux = x - p.x;
      p.vx = p.dux / dt;
    } else {
      p.dux = eq19 ? move_increment<true>(p.dux, p.vx, dt) : move_increment<false>(p.dux, p.vx, dt);
    }
    p.x += p.dux;
    place_plate(geometry.walls[p.wall], p);
    ObstacleMotion& m = moving.motion[p.wall];
    m.dux = p.dux;
    m.duy = p.duy;
    m.dtheta = 0;
  }
  // Prescribed translations: this step runs from steps dt to (steps + 1) dt (the clock counted in
  // steps, so that a window given in whole steps moves the wall in exactly those steps).
  const double t1 = static_cast<double>(steps + 1) * dt;
  for (TranslatingWall& q : moving.translating) {
    const double s1 = q.moved(t1);
    const double x1 = q.vx * s1, y1 = q.vy * s1;
    ObstacleMotion& m = moving.motion[q.wall];
    m.dux = x1 - q.x;
    m.duy = y1 - q.y;
    m.dtheta = 0;
    q.x = x1;
    q.y = y1;
    place_translated(geometry.walls[q.wall], q);
  }
}

void World::place_moving_walls() {
  for (const RotatingWall& r : moving.rotating) place_rotated(geometry.walls[r.wall], r);
  for (const RigidPlate& p : moving.plates) place_plate(geometry.walls[p.wall], p);
  for (TranslatingWall& q : moving.translating) {  // where the clock says
    const double s = q.moved(static_cast<double>(steps) * dt);
    q.x = q.vx * s;
    q.y = q.vy * s;
    place_translated(geometry.walls[q.wall], q);
  }
}

bool World::walls_moved_far() const {
  const double lim = 0.5 * neighbors.skin;
  for (const RotatingWall& r : moving.rotating)
    if (std::abs(r.theta - r.theta_listed) * r.reach > lim) return true;
  for (const RigidPlate& p : moving.plates)
    if (std::hypot(p.x - p.x_listed, p.y - p.y_listed) > lim) return true;
  for (const TranslatingWall& q : moving.translating)
    if (std::hypot(q.x - q.x_listed, q.y - q.y_listed) > lim) return true;
  return false;
}

void World::walls_listed() {
  for (RotatingWall& r : moving.rotating) r.theta_listed = r.theta;
  for (RigidPlate& p : moving.plates) {
    p.x_listed = p.x;
    p.y_listed = p.y;
  }
  for (TranslatingWall& q : moving.translating) {
    q.x_listed = q.x;
    q.y_listed = q.y;
  }
}

}  // namespace dem
