// integrator.scheme = "velocity_verlet_onset": velocity Verlet, second order in a collision.
//
// Velocity Verlet integrates a contact's force by the trapezoid rule, dt/2 (F(t) + F(t + dt)),
// which is second order only where the force is smooth. A collision breaks that three ways, each
// an error of order dt / t_c in the restitution (docs/scene.md, benchmarks/README.md):
//  1. the dashpot at t + dt sees v(t + dt/2), half a step late;
//  2. a contact that starts inside the step: the force is 0 before and jumps to the dashpot's
//     eta_n v_n at the touch, so the trapezoid over the whole step is wrong by O(eta_n v_n dt);
//  3. a slip that starts inside the step: the shear dashpot switches off there (eq. 13b), a jump
//     of eta_s v_s.
// This scheme keeps Verlet's half kick, drift and half kick, and changes what the contacts give:
//  1. the dashpots see the predicted v(t + dt) = 2 v(t + dt/2) - v(t) (= v(t) + a(t) dt, an error
//     of O(dt^2)); the springs still take the increments v(t + dt/2) dt;
//  2. a contact apart at t (overlap - du_n < 0) touched for the fraction phi = overlap / du_n of
//     the step: its shear spring takes phi du_s, and the step's impulse becomes the trapezoid over
//     the part in contact, phi dt/2 (F_touch + F(t + dt)), F_touch the law at zero overlap with
//     the dashpots alone; the missed impulse (onset_impulse) is added with the closing half kick;
//  3. a contact that stuck at t and slides at t + dt started to slide at the fraction theta where
//     the spring met the cap (both linear over the step); the impulse becomes the trapezoid of
//     each part (slip_impulse). The cap at t is the law's own: discs on walls and points keep
//     their f_n; disc pairs under friction_cap = "elastic" have it from e_n (overlap spring),
//     under friction_cap = "total" from the f_n the pass kept for each touching pair
//     (World::onset_normals, pair_normals.hpp). The very value, not one rebuilt from the state:
//     a sliding contact's |e_s| is the last cap to the bit, and a cap off by O(dt^2) would give
//     it a spurious impulse of O(dt) at every step.
// The pass runs on one thread (the same bits at every thread count); the move is Verlet's.
// The scheme's contacts are onset_stage.hpp, compiled in the kernel list's rows (kernel_list.cpp).
#include <vector>

#include "physics/world.hpp"

namespace dem {

void World::step_onset() {
  Discs& d = discs;
  // The discs in cell order when theirs has decayed: before v(t) is kept, which is in the discs'
  // order (step() checks after its lists' refresh; here the last step left them fresh).
  if (steps % DiscOrderRule::kCheckEvery == 0) check_disc_order();
  onset_vx_ = d.vx;  // v(t): the dashpots' prediction 2 v(t + dt/2) - v(t)
  onset_vy_ = d.vy;
  onset_om_ = d.omega;
  bool far = move_discs(Move::kick_drift_eq18, 0.5 * dt);  // (17) v(t + dt/2); (18) du = v(t + dt/2) dt; x += du
  refresh_lists(far);
  if (steps % kRebalanceEvery == 0) balance_blocks();
  if (measure_increments) measure_increment_sums();  // the move's |v dt|, before the kick overwrites v
  onset_forces();                                     // F(t + dt) and the missed impulses
  far = move_discs(Move::kick, 0.5 * dt);             // (17) v(t + dt)
  const int* kd = d.kind.empty() ? nullptr : d.kind.data();
  for (std::size_t i = 0; i < d.size(); ++i) {        // and the missed impulses (held discs: 1/m = 0)
    const int k = kd ? kd[i] : 0;
    d.vx[i] += onset_jx_[i] * d.kinds.inv_mass[k];
    d.vy[i] += onset_jy_[i] * d.kinds.inv_mass[k];
    d.omega[i] += onset_jt_[i] * d.kinds.inv_inertia[k];
  }
  if (far) rebuild_lists();
  time += dt;
  ++steps;
  if (measure_increments) increments_measured_step_ = steps;
  particle_steps += static_cast<double>(d.size());
}

void World::onset_forces(bool start) {
  if (start) {  // v(t) itself is the dashpots' velocity: 2 v - v
    onset_vx_ = discs.vx;
    onset_vy_ = discs.vy;
    onset_om_ = discs.omega;
  }
  (this->*kernel_->onset)(start);  // the row's pass (kernels.hpp; prepare() checks it has one)
}

}  // namespace dem
