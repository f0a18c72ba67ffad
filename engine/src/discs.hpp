// Disc state as flat arrays (structure of arrays): the step streams through these.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace dem {

struct Discs {
  // Constant per disc.
  std::vector<double> r;         // radius [cm]
  std::vector<double> mass;      // rho pi r^2 [g per cm of thickness]
  std::vector<double> inv_mass;  // 1/m
  std::vector<double> inv_inertia;  // 1/I, I = m r^2 / 2
  std::vector<int> material;     // index into the scene's materials
  std::vector<int> id;           // stable id (survives removals)
  // Kinematics.
  std::vector<double> x, y, phi;       // position [cm], rotation [rad], counter-clockwise
  std::vector<double> vx, vy, omega;   // velocities
  std::vector<double> dux, duy, dphi;  // last increments du, dv, dphi: eq. 19 only (World::increments)
  // Resultants of eq. (15), gravity included.
  std::vector<double> fx, fy, torque;

  std::size_t size() const { return r.size(); }
  void add(double px, double py, double radius, double density, int mat) {
    const double m = density * 3.14159265358979323846 * radius * radius;
    r.push_back(radius);
    mass.push_back(m);
    inv_mass.push_back(1.0 / m);
    inv_inertia.push_back(2.0 / (m * radius * radius));
    material.push_back(mat);
    id.push_back(static_cast<int>(id.size()));
    x.push_back(px); y.push_back(py); phi.push_back(0);
    for (auto* v : {&vx, &vy, &omega, &dux, &duy, &dphi, &fx, &fy, &torque}) v->push_back(0);
  }
};

// The moving part of the disc state (positions, rotations, velocities) of the same discs: what a
// run keeps of its last good state, at 48 bytes a disc instead of a whole copy.
struct Kinematics {
  std::vector<double> x, y, phi, vx, vy, omega;

  std::size_t size() const { return x.size(); }
  // The six arrays in one order (what a checkpoint writes and reads).
  std::array<std::vector<double>*, 6> arrays() { return {&x, &y, &phi, &vx, &vy, &omega}; }
  std::array<const std::vector<double>*, 6> arrays() const { return {&x, &y, &phi, &vx, &vy, &omega}; }
  void take(const Discs& d) {
    x = d.x; y = d.y; phi = d.phi;
    vx = d.vx; vy = d.vy; omega = d.omega;
  }
  // The discs d with these positions and velocities (d must be the same discs: same count).
  void put_into(Discs& d) const {
    d.x = x; d.y = y; d.phi = phi;
    d.vx = vx; d.vy = vy; d.omega = omega;
  }
};

}  // namespace dem
