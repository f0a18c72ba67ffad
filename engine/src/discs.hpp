// Disc state as flat arrays (structure of arrays): the step streams through these.
#pragma once

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
  // Room for n discs exactly (a fill of known count): no doubling slack, about 5 % at 1M discs.
  void reserve(std::size_t n) {
    for (auto* v : {&r, &mass, &inv_mass, &inv_inertia, &x, &y, &phi, &vx, &vy, &omega, &dux, &duy, &dphi, &fx, &fy, &torque})
      v->reserve(n);
    material.reserve(n);
    id.reserve(n);
  }
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

}  // namespace dem
