// The simulated world and its time step.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "physics/clusters.hpp"
#include "physics/disc_order.hpp"
#include "physics/discs.hpp"
#include "physics/geometry.hpp"
#include "physics/integrator.hpp"
#include "physics/kernels.hpp"
#include "physics/model.hpp"
#include "physics/moving_walls.hpp"
#include "physics/neighbors.hpp"
#include "physics/pair_normals.hpp"
#include "physics/pair_totals.hpp"

namespace dem {

// A block of touching pairs on its way through the law (World::pair_contacts): the gathered geometry
// and history in, the forces out. 128 pairs: some 20 kB, on the stack of the thread that runs the
// pass (hot in its own cache; one vector of blocks for all threads, on the heap, makes the second
// thread's pass 1.8x slower than the first's).
struct alignas(64) PairBlock {
  static constexpr int kSize = 128;
  int pair[kSize];  // offset in the pass's part of the list (the cross pass: in its list of pairs)
  int gap[kSize];   // a recorded pass: offsets of the touching pairs another block computes (cross pairs)
  int prop[kSize];  // index of the pair's constants (several kinds of disc)
  double dx[kSize], dy[kSize], R2[kSize], sum[kSize];  // (3): x_j - x_i, y_j - y_i, R^2, r_i + r_j (several kinds)
  // (5): the increments du_i, du_j, dv_i, dv_j, dphi_i, dphi_j as increments() stores them (the law
  // multiplies them by its factor: eight pairs a vector instead of one at a time).
  double dui[kSize], duj[kSize], dvi[kSize], dvj[kSize], rot_i[kSize], rot_j[kSize];
  // arm_i, arm_j: the radii in (several kinds); LeverArm::contact_point: the lever arms r -
  // overlap/2 out.
  double arm_i[kSize], arm_j[kSize];
  double en[kSize], es[kSize];  // history in, history out
  double overlap[kSize], fn[kSize], fs[kSize], fx[kSize], fy[kSize];  // out: fx, fy on i
};

class World {
 public:
  Discs discs;
  Geometry geometry;
  Neighbors neighbors;
  int n_materials = 1;
  std::vector<PairProps> props;  // n_materials x n_materials, symmetric
  ContactOptions options;
  // Paper 2's cluster bonds, sorted by (i, j); never in the neighbour lists. Empty: no bond code.
  std::vector<Bond> bonds;
  // Moving walls and plates (shear box). Empty: fixed geometry, no wall-motion code.
  MovingWalls moving;
  Scheme scheme = Scheme::paper_eq19;
  double dt = 1e-4;         // [s]
  // Integrate each disc's rotation angle phi (the last line of eqs. 18, 19), an output only: the
  // law reads the increments, never the angle. Off: Discs::phi is empty and the drift skips it
  // (output.rotation_angle).
  bool rotation_angle = false;
  // Threads of the force and integration loops (OpenMP; run.threads, --threads). Every count
  // gives the bits of the plain serial loop (1): each disc's forces are summed in the serial
  // order (forces_then_move), and sums over the discs have blocks of their own (parallel_sum).
  // Scenes with bonds or moving walls, and worlds under kMinDiscsPerThread discs a thread, run
  // serial.
  int threads = 1;
  // At most this many of them now (a run's thread choice, run/thread_choice.hpp); 0: threads.
  int threads_allowed = 0;
  static constexpr int kMinDiscsPerThread = 2048;
  // Doubles a vector in the pair law and the integration loops: 8 (AVX-512), 4 (AVX2) or 2
  // (SSE2), the widest the processor has (cpu_vector_width), chosen once at start-up; the same
  // bits at every width. Tests and benchmarks may run a world at a narrower one (set_vector_width).
  static const int vector_width;
  static int cpu_vector_width();
  void set_vector_width(int width);  // 2, 4 or 8, at most vector_width
  int vector_width_used() const { return width_; }
  int threads_for(int n) const;  // the thread count used for n discs
  double gx = 0, gy = -980; // gravity [cm/s^2]
  // Whether the discs are put in cell order when their order has lost its locality
  // (disc_order.hpp; integrator.disc_order): evaluated every DiscOrderRule::kCheckEvery steps.
  // The arrays are then in the engine's order; ids (Discs::id) keep the user's, and every output
  // lists the discs by id.
  DiscOrder disc_order = DiscOrder::automatic;
  long resorts = 0;  // re-sorts so far (summary.json disc_resorts)
  // The rule now: re-sorts when the spread is above the limit (disc_order.hpp).
  void check_disc_order();
  // Puts the discs in cell order now (what the rule does; public for tests).
  void resort_discs();

  double time = 0;
  long steps = 0;
  double particle_steps = 0;  // sum over steps of the number of discs (throughput)
  double max_overlap = 0;  // largest overlap seen by the last force computation [cm]

  // The total forces of the pairs that touched in the force pass of step `pair_forces_step`, in
  // the list's order (PairTotals: 16 bytes a touching pair while the list is the pass's). They are
  // outputs, not history (the next step needs e_n and e_s alone), so a pass records them only
  // when record_pair_forces is set: the run loops set it before the steps whose contacts they
  // write or read. Keeping them in the pair list cost 16 bytes a pair and a third of the force
  // pass's memory traffic.
  bool record_pair_forces = false;
  PairTotals pair_totals;
  long pair_forces_step = -1;
  bool pair_forces_current() const { return pair_forces_step == steps; }
  // velocity_verlet_onset under friction_cap = "total" alone: each touching pair's f_n at the end
  // of the last step, the cap at the next step's start of its slip correction (onset.cpp). History,
  // not output: removals and re-sorts carry it, state files and checkpoints hold it. Empty otherwise.
  PairNormals onset_normals;

  // The threads' blocks of discs in the force pass (thread t owns discs [force_blocks[t],
  // force_blocks[t + 1]); empty with one thread). Set every kRebalanceEvery steps so that each
  // block has about the same work: a disc 1 unit, a pair that touched in the last pass (non-zero
  // history) 1 more, on its i. Equal numbers of discs leave a settled silo's lower half (its pairs
  // in contact) to one thread and the looser top to the other: 12.8 against 4.5 ms a step at 1M
  // discs. The law runs eight pairs a vector, so a touching pair costs about what a disc does:
  // weighed at 3 units a pair against 1 a disc, the thread of the upper, looser discs has 1.6
  // times the other's work at 1M discs (perf). The blocks set no sum's order (a disc's forces are
  // added in the serial order whatever its block), only who computes what: they are saved with
  // the state and remapped, not rebuilt, on removals, so that a resumed run keeps the balance of
  // the run in one piece.
  std::vector<int> force_blocks;
  static constexpr long kRebalanceEvery = 64;
  bool blocks_fit() const;  // force_blocks fit the thread count and the discs
  void balance_blocks();  // force_blocks from the lists as they are
  // f(p, rec) for each pair p of the list, in order, with its recorded totals rec (nullptr for a
  // pair the recorded pass found apart or did not have).
  template <class F>
  void each_pair_with_forces(F&& f) const {
    PairTotals::Cursor r;
    for (std::size_t p = 0; p < neighbors.pairs.size(); ++p) f(p, pair_totals.at(neighbors.pairs, p, r));
  }
  // f(i, j, fn, fs) for each recorded total, in (i, j) order.
  template <class F>
  void each_recorded_pair(F&& f) const { pair_totals.each(neighbors.pairs, f); }
  std::vector<PairForce> recorded_pairs() const { return pair_totals.records(neighbors.pairs); }  // (tests)

  const PairProps& pair(int a, int b) const { return props[a * n_materials + b]; }
  // The kernel list (kernels.hpp) by name: its force rows, then its move rows, in its order; and
  // the force row this world runs (select_kernel, at prepare()).
  static std::vector<std::string> kernel_names();
  const std::string& kernel_name() const;
  // What the selected kernel computes (for the header and the skip benchmark).
  bool kernel_shear = true, kernel_dashpots = true;
  // Selects the specialised force kernel and computes the first forces (call before step()).
  void init();
  // The same without computing forces: for a state restored with its forces and history. Without
  // build_lists the contact lists are taken as they are (a checkpoint restores them exactly).
  void prepare(bool build_lists = true);
  // Puts the moving walls where their restored angles and plate displacements say (state files),
  // and the translating walls where the clock (steps dt) says.
  void place_moving_walls();
  // One time step: the algorithm as a list of stages (step.cpp).
  void step();
  // Velocity Verlet's closing half kick (17) of the discs, left owed by a step: the next step's
  // first sweep gives it with its own half kick, in one pass over the arrays instead of two, the
  // same operations in the same order (the same bits); pay_kick() gives it alone. While it is
  // owed, vx, vy, omega hold v(t - dt/2) and the resultants f(t) (velocity_now gives a disc's
  // v(t)): whoever sets defer_closing_kick (the run loop, Runner::run) pays before anything
  // reads the velocities. Other schemes, moving walls and bonds never owe it.
  bool defer_closing_kick = false;
  bool kick_owed() const { return kick_owed_; }
  void pay_kick();
  // Disc i's velocity at the step's end, the owed kick included (the same bits as pay_kick).
  void velocity_now(std::size_t i, double& vx, double& vy) const;
  // Throws std::logic_error naming `who` while the kick is owed: a reader of v(t) that did not pay.
  void require_velocities(const char* who) const;
  // Recomputes the forces from the last increments (as the start of a step does); for tests.
  void compute_forces_now() { forces_then_move(Move::none, 0.0); }
  // The move of the discs alone (public for the kernel benchmarks, benchmarks/kernels.cpp): the
  // kick v += a h of eq. 17 and a drift. They return whether some disc is now more than skin/2
  // from where the lists were built (the lists must be rebuilt before the next force pass).
  bool kick_drift_eq18(double h) { return move_discs(Move::kick_drift_eq18, h); }  // du = v dt, eq. (18); x += du
  bool kick_drift_eq19(double h) { return move_discs(Move::kick_drift_eq19, h); }  // du = (du + v dt) / 2, eq. (19)

  // Removes the discs of `removed` from every array (order kept; lists remapped).
  void remove_discs(const RemovedDiscs& removed);
  // Removes a wall (the slit's gate) from the computation; false if there is no such wall.
  bool deactivate_wall(const std::string& name);

  // The increments du, dv, dphi of the last move (eqs. 5), as arrays times a factor. Eq. (19)
  // keeps its own (the mean of the last one and v dt: Discs::dux, duy, dphi, factor 1). Eq. (18)
  // and Verlet move by exactly v dt, and that v is still in vx, vy, omega when the forces and the
  // rest measure read it: they read v and multiply by dt (the same bits), and keep no increment
  // arrays (24 bytes a disc).
  struct Increments {
    const double *x, *y, *phi;
    double factor;
  };
  Increments increments() const;
  // Paper's rest measure (note 3): mean over discs of |du| and |dv| of the last step. Verlet's
  // closing half kick overwrites the v of its move, so a Verlet step adds them up before it
  // when measure_increments is set (the run loop sets it for its check steps); otherwise the
  // last step must be of another scheme.
  void mean_abs_increment(double& mx, double& my) const;
  bool measure_increments = false;
  double kinetic_energy() const;
  bool all_finite() const;

 private:
  // A thread's share of a force pass (serial: one block of everything): its discs [i0, i1)
  // (force_blocks), their pairs [p0, p1) and wall entries [w0, w1) of the lists.
  struct ForceBlock {
    int t = 0, threads = 1;  // this block's thread, of `threads`
    int i0 = 0, i1 = 0;
    std::size_t p0 = 0, p1 = 0, w0 = 0, w1 = 0;
    PairTotals::Force* record = nullptr;     // a recorded pass: this block's first pair total
    std::vector<PairTotals::Force*>* gaps = nullptr;  // a recorded pass with threads: cross pairs' totals (CrossPair)
    double pair_overlap = 0, wall_overlap = 0;  // the largest overlaps (max_overlap)
  };
  // A cross pair: a pair of a block's part of the list whose j is in a later block `to`; j's
  // block computes it (its cross pass), at `at` in its list of cross pairs.
  struct CrossPair {
    std::size_t q;  // in the pair list
    int i, to;
    std::size_t at;
  };
  struct CrossForce {  // a cross pair's result for i's block: the force on i, the moment, the totals
    double fx, fy, tq, fn, fs;
    bool touching;
  };
  // A stage of a force pass on one block, and the pair law on a block of pairs (PairBlock).
  using Stage = void (World::*)(ForceBlock&);
  using PairLaw = void (*)(PairBlock&, int n, const PairProps* props, double inv_dt, double sum1, double uf);
  // The law on one contact, (6)-(14) (contact_law.hpp), as the wall stage calls it.
  using ContactLaw = void (*)(const PairProps& p, double overlap, double du_n, double du_s, double inv_dt, double& en,
                              double& es, double& fn, double& fs);
  // A force row of the kernel list: the stages compiled for one law and feature set (kernels.hpp).
  struct Kernel {
    KernelKey key;
    std::string name;
    Stage pairs[2][2] = {};       // [recorded pass][one kind of disc]
    Stage cross[2] = {};          // [one kind of disc]: the block's cross pairs (threads)
    Stage walls = nullptr;
    Stage bonds = nullptr;        // none without bonds
    PairLaw pair_law[3][2] = {};  // [vector width 2, 4, 8][one kind of disc]: what pairs runs
    ContactLaw contact_law = nullptr;  // what walls runs
    void (World::*onset)(bool start) = nullptr;  // velocity_verlet_onset's pass (overlap spring, no bonds or moving walls)
  };
  static const std::vector<Kernel>& kernels();  // the force rows, kKernelCount in kernels.hpp's order
  template <std::size_t K>
  static Kernel make_kernel();
  const Kernel* kernel_ = nullptr;  // this world's row (select_kernel)
  int width_ = vector_width;        // this world's vector width
  int width_index() const { return width_ == 8 ? 2 : width_ == 4 ? 1 : 0; }
  void select_kernel();

  // The stages of a step (step.cpp shows them in order).
  void refresh_lists(bool far);  // the lists rebuilt where stale or where something moved skin/2
  // The force stages and the move, fused per block; `started`: the resultants already hold m_i g
  // and a zero torque (the move before wrote them: move_discs' reset).
  bool forces_then_move(Move move, double h, bool started = false);
  template <class F>
  bool each_block(int nt, F&& stages);  // stages(block) for each thread's block; whether some disc is far
  void start_resultants(int i0, int i1);  // the m_i g of (15) and a zero torque
  void start_recording(ForceBlock& b);    // where a recorded pass puts the block's pair totals
  // Disc pairs: (3)-(15), the law the row's (Kernel::pair_law). CROSS: the pairs of earlier
  // blocks whose j is in this block (cross_in_).
  template <LeverArm LA, bool SHEAR, bool RECORD, bool ONE_KIND, bool CROSS = false>
  void pair_contacts(ForceBlock& b);
  template <LeverArm LA, bool SHEAR, bool RECORD, bool ONE_KIND, bool CROSS>
  struct PairPass;  // a pair stage's arrays and sub-steps
  template <LeverArm LA, bool MOVING, bool SHEAR>
  void wall_contacts(ForceBlock& b);      // discs on walls and points: (3)-(15), the row's contact_law
  template <NormalSpring NS>
  void bond_contacts(ForceBlock& b);      // paper 2's bonds: (4), (5), the bond law, (15)
  void map_cross_pairs(ForceBlock& b);    // cross_out_, cross_in_ for the blocks and lists as they are
  void add_cross_forces(ForceBlock& b);   // the forces on the block's discs of its cross pairs, computed by later blocks
  // (16)-(19) for discs [i0, i1); reset: the kick's forces, once read, set to the next pass's
  // start (start_resultants) in the same sweep (velocity Verlet's first half step).
  // owed: the owed closing half kick first (kick_owed), in the same sweep.
  bool move_block(Move move, double h, int i0, int i1, bool reset = false, bool owed = false);
  bool move_discs(Move move, double h, bool reset = false, bool owed = false);  // move_block on equal blocks, one parallel region
  bool kick_owed_ = false;  // see defer_closing_kick
  double owed_h_ = 0;       // [s] the owed kick's h (dt/2 of the step that owes it)
  // velocity_verlet_onset (onset.cpp): its step, and its force pass (one thread): the forces at
  // t + dt with the dashpots on the predicted v(t + dt), and the impulses a contact or a slip that
  // started inside the step missed (onset_jx, jy, jt), added with the closing half kick.
  void step_onset();
  // start: the forces at the run's start (World::init): the dashpots on v(t), no spring increment.
  void onset_forces(bool start = false);
  template <NoTension NT, FrictionCap FC, LeverArm LA>
  void onset_forces_law(bool start);
  template <NoTension NT, FrictionCap FC, LeverArm LA>
  void onset_pairs(double hs, double& worst);  // its disc pairs; worst: the largest overlap
  template <NoTension NT, FrictionCap FC, LeverArm LA>
  void onset_walls(double hs, double& worst);  // its discs on walls and points
  std::vector<double> onset_vx_, onset_vy_, onset_om_;  // v(t) of the step's start (not state: set each step)
  std::vector<double> onset_jx_, onset_jy_, onset_jt_;  // the step's missed impulses (x, y, moment)
  void move_walls(Move move, double h);   // (16)-(19) for the plates, the prescribed turns (world_walls.cpp)

  // (3), the one test of both: a pair is apart when R^2 > (r_i + r_j)^2 (a NaN counts as touching).
  static bool apart(double R2, double sum) { return R2 > sum * sum; }
  std::size_t touching_pairs(std::size_t p0, std::size_t p1) const;  // pairs of [p0, p1) that touch now
  void size_pair_forces(std::size_t count);  // room for exactly count recorded totals over the list
  void drop_pair_forces();  // frees the recorded totals (pair_forces_current() is false after)
  std::vector<Padded<std::size_t>> touching_;  // per thread: touching pairs of a recorded pass
  // Every disc of one kind: the kernels keep its constants in registers instead of reading them
  // through each disc's kind.
  bool one_kind() const { return discs.kinds.size() == 1; }
  void measure_increment_sums();  // Verlet: sums of |v dt| of parallel_sum's blocks, before the closing kick
  std::vector<Padded<std::array<double, 2>>> increment_sums_;  // by parallel_sum's blocks
  long increments_measured_step_ = -1;
  // Per block (thread): its cross pairs in list order; the cross pairs it computes (earlier
  // blocks' pairs with j here, block by block in list order) and their results. Set at the first
  // pass with threads after a list build, a balance or a removal (cross_ok_ false).
  std::vector<Padded<std::vector<CrossPair>>> cross_out_;
  std::vector<Padded<std::vector<std::size_t>>> cross_in_;
  std::vector<Padded<std::vector<CrossForce>>> cross_forces_;
  std::vector<Padded<std::vector<PairTotals::Force*>>> cross_gaps_;  // a recorded pass: where cross_out_'s touching totals go
  bool cross_ok_ = false;
  std::vector<double> thread_overlap_;            // per thread: largest overlap of the last pass
  void rebuild_lists();       // neighbour lists without the bonded pairs
  bool walls_moved_far() const;  // some wall moved skin/2 since the lists were built
  void walls_listed();        // remember the wall positions of this list build
  bool adjacent(int k1, int k2) const;  // a wall and a point at its end
  // Per thread: per wall entry of one disc, touching now and its centre distance.
  std::vector<std::vector<char>> touch_scratch_;
  std::vector<std::vector<double>> dist_scratch_;
};

}  // namespace dem
