// The simulated world and its time step.
#pragma once

#include <string>
#include <vector>

#include "discs.hpp"
#include "geometry.hpp"
#include "model.hpp"
#include "neighbors.hpp"

namespace dem {

class World {
 public:
  Discs discs;
  Geometry geometry;
  Neighbors neighbors;
  int n_materials = 1;
  std::vector<PairProps> props;  // n_materials x n_materials, symmetric
  ContactOptions options;
  Scheme scheme = Scheme::paper_eq19;
  double dt = 1e-4;         // [s]
  double gx = 0, gy = -980; // gravity [cm/s^2]

  double time = 0;
  long steps = 0;
  double particle_steps = 0;  // sum over steps of the number of discs (throughput)
  double max_overlap = 0;  // largest overlap seen by the last force computation [cm]

  const PairProps& pair(int a, int b) const { return props[a * n_materials + b]; }
  // Selects the specialised force kernel and computes the first forces (call before step()).
  void init();
  // The same without computing forces: for a state restored with its forces and history.
  void prepare();
  // One time step; the whole algorithm is here.
  void step();

  // Removes the discs with dead[i] != 0 from every array (order kept; lists remapped).
  void remove_discs(const std::vector<char>& dead);
  // Removes a wall (the slit's gate) from the computation; false if there is no such wall.
  bool deactivate_wall(const std::string& name);

  // Paper's rest measure (note 3): mean over discs of |du| and |dv| of the last step.
  void mean_abs_increment(double& mx, double& my) const;
  double kinetic_energy() const;
  bool all_finite() const;

 private:
  using ForceKernel = void (World::*)();
  ForceKernel force_kernel_ = nullptr;
  template <NormalSpring NS, NoTension NT, FrictionCap FC>
  void compute_forces();
  void select_kernel();
  bool adjacent(int k1, int k2) const;  // a wall and a point at its end
  std::vector<char> touch_scratch_;   // per wall entry of one disc: touching now
  std::vector<double> dist_scratch_;  // ... and its centre distance
  void kick(double h);        // v += a h  (eq. 17 with h = dt)
  void drift_eq18();          // du = v dt, eq. (18); x += du
  void drift_eq19();          // du = (du + v dt) / 2, eq. (19); x += du
};

}  // namespace dem
