// The time step as a list of stages, and the threads' blocks of discs that run them
// (docs/architecture-kernels.md).
#include <algorithm>

#include "physics/parallel.hpp"
#include "physics/world.hpp"

namespace dem {

// One time step. Eqs. (18) and (19) take the forces from the increments of the last move and
// then move; velocity Verlet moves first (half kick, drift), takes the forces at the new
// positions and closes with a half kick. The forces and the move after them are fused
// (forces_then_move): each thread takes its block of discs through all their stages in one
// parallel region, a fork and join being as dear as a small world's whole pass.
void World::step() {
  if (scheme == Scheme::velocity_verlet_onset) return step_onset();  // onset.cpp
  const bool verlet = scheme == Scheme::velocity_verlet;
  bool far = false;  // some disc is now skin/2 from its list position
  if (verlet) {
    if (kick_owed_ && owed_h_ != 0.5 * dt) pay_kick();  // dt changed: the owed kick with its own h
    // (17) the last step's closing half kick if owed, then v(t + dt/2); (18) du = v(t + dt/2) dt;
    // x += du; the resultants' start, m_i g, in the same sweep
    far = move_discs(Move::kick_drift_eq18, 0.5 * dt, true, kick_owed_);
    kick_owed_ = false;
    move_walls(Move::kick_drift_eq18, 0.5 * dt);
  }
  refresh_lists(far);                                    // the candidates of (3)
  if (steps % DiscOrderRule::kCheckEvery == 0) check_disc_order();  // the discs in cell order when theirs has decayed
  if (steps % kRebalanceEvery == 0) balance_blocks();    // the threads' blocks (and whenever they do not fit)
  if (verlet && measure_increments) measure_increment_sums();  // the move's |v dt|, before the kick overwrites v
  const Move move = verlet ? Move::kick : scheme == Scheme::paper_eq18 ? Move::kick_drift_eq18 : Move::kick_drift_eq19;
  const double h = verlet ? 0.5 * dt : dt;
  // Verlet's closing half kick (17) of the discs owed to the next step's first sweep (defer_closing_kick)
  const bool owe = verlet && defer_closing_kick && moving.empty() && bonds.empty();
  far = forces_then_move(owe ? Move::none : move, h, verlet);  // (3)-(15), then (16)-(19) for the discs
  if (owe) {
    kick_owed_ = true;
    owed_h_ = h;
  }
  move_walls(move, h);                                   // (16)-(19) for the plates; the walls' turns
  if (far) rebuild_lists();                              // for the next step's forces
  time += dt;
  ++steps;
  if (measure_increments && verlet) increments_measured_step_ = steps;
  particle_steps += static_cast<double>(discs.size());
}

// The stages of a force pass and the move, for each block of discs: the row of the kernel list
// this scene runs (select_kernel) says which code each force stage is. A disc's forces are summed
// in the serial order whatever the blocks: m g, its pairs in list order (those (h, i) before those
// (i, j), each by the other disc), its walls. With threads a block first computes its cross pairs
// (h of an earlier block, i its own: the first of i's pairs in that order), then its own pairs,
// and once every block is done adds the forces of its discs' pairs with a later block's j (the
// last of their pairs), then the walls.
bool World::forces_then_move(Move move, double h, bool started) {
  const Kernel& k = *kernel_;
  const bool record = record_pair_forces;
  // Totals recorded by an earlier pass are stale after this one (pair_forces_current is false):
  // freed, so that they never sit beside a list build's scratch (one or the other at the peak).
  if (!record && pair_totals.allocated()) drop_pair_forces();
  const Stage pairs = k.pairs[record][one_kind()];
  // Bonds and moving walls run on one thread: their stages reach across any block.
  const bool serial = k.key.features.bonds || k.key.features.moving_walls;
  const bool far = each_block(serial ? 1 : threads_for(static_cast<int>(discs.size())), [&](ForceBlock& b) {
    if (!started) start_resultants(b.i0, b.i1);              // (15): m_i g in X_i, Y_i; M_i = 0
    if (record) start_recording(b);
    if (b.threads > 1) (this->*k.cross[one_kind()])(b);      // (3)-(15) the block's cross pairs
    (this->*pairs)(b);                                       // (3)-(15) disc pairs
    if (k.bonds) (this->*k.bonds)(b);                        // paper 2's bonds: the law without (8), (13)
    add_cross_forces(b);                                     // the cross pairs of later blocks, on i
    (this->*k.walls)(b);                                     // (3)-(15) discs on walls and points
    return move_block(move, h, b.i0, b.i1);                  // (16)-(19)
  });
  // A step's pass (it moves, or Verlet's first sweep started it): the step it ends.
  if (record) pair_forces_step = steps + (move != Move::none || started ? 1 : 0);
  return far;
}

void World::refresh_lists(bool far) {
  if (!moving.empty() && walls_moved_far()) neighbors.invalidate();
  if (far || neighbors.stale(discs)) {
    drop_pair_forces();  // the last step's totals, stale once this step runs: never beside a build's scratch
    rebuild_lists();
  }
}


// Threads own contiguous blocks of discs (force_blocks: of equal work, set every kRebalanceEvery
// steps); a pair is computed by the owner of its i, a cross pair (j in a later block) by the
// owner of its j (forces_then_move).
template <class F>
bool World::each_block(int nt, F&& stages) {
  const int n = static_cast<int>(discs.size());
  const auto& pairs = neighbors.pairs;
  const auto& wl = neighbors.walls;
  if (nt == 1) {
    ForceBlock b;
    b.i1 = n;
    b.p1 = pairs.size();
    b.w1 = wl.size();
    const bool far = stages(b);
    max_overlap = std::max(b.pair_overlap, b.wall_overlap);
    return far;
  }
  if (!blocks_fit()) balance_blocks();  // other threads or discs than at the last balance
  const bool map = !cross_ok_;
  std::vector<double>& part = thread_overlap_;
  part.assign(nt, 0.0);
  unsigned far = 0;
#pragma omp parallel num_threads(nt) reduction(| : far)
  {
    ForceBlock b;
    b.t = omp_thread_index();
    b.threads = nt;
    b.i0 = force_blocks[b.t];
    b.i1 = force_blocks[b.t + 1];
    const auto by_i = [](const auto& c, int i) { return c.i < i; };
    b.p0 = std::lower_bound(pairs.begin(), pairs.end(), b.i0, by_i) - pairs.begin();
    b.p1 = std::lower_bound(pairs.begin(), pairs.end(), b.i1, by_i) - pairs.begin();
    b.w0 = std::lower_bound(wl.begin(), wl.end(), b.i0, by_i) - wl.begin();
    b.w1 = std::lower_bound(wl.begin(), wl.end(), b.i1, by_i) - wl.begin();
    if (map) map_cross_pairs(b);
    far |= stages(b) ? 1u : 0u;
    part[b.t] = std::max(b.pair_overlap, b.wall_overlap);
  }
  cross_ok_ = true;
  double worst = 0;
  for (int t = 0; t < nt; ++t) worst = std::max(worst, part[t]);
  max_overlap = worst;
  return far != 0;
}

// A recorded pass: each thread writes its touching pairs' totals into its own slice of
// pair_totals, sized once to the exact count (the list's order; no growth, no copy).
void World::start_recording(ForceBlock& b) {
  if (b.threads == 1) {
    size_pair_forces(touching_pairs(b.p0, b.p1));
    b.record = pair_totals.forces();
    return;
  }
  touching_[b.t].value = touching_pairs(b.p0, b.p1);
#pragma omp barrier
  if (b.t == 0) {  // the main thread: its malloc arena, where the list is freed again
    std::size_t total = 0;
    for (int u = 0; u < b.threads; ++u) total += touching_[u].value;
    size_pair_forces(total);
  }
#pragma omp barrier
  std::size_t offset = 0;
  for (int u = 0; u < b.t; ++u) offset += touching_[u].value;
  b.record = pair_totals.forces() + offset;
  b.gaps = &cross_gaps_[b.t].value;
  b.gaps->clear();
}

// Each block's cross pairs, then each block's list of the cross pairs it computes: those of the
// earlier blocks, block by block, in list order (so that a disc j gets them by increasing i).
void World::map_cross_pairs(ForceBlock& b) {
  const auto& pairs = neighbors.pairs;
  std::vector<CrossPair>& out = cross_out_[b.t].value;
  out.clear();
  for (std::size_t p = b.p0; p < b.p1; ++p)
    if (pairs[p].j >= b.i1) {
      const int to = static_cast<int>(std::upper_bound(force_blocks.begin(), force_blocks.end(), pairs[p].j) -
                                      force_blocks.begin()) - 1;
      out.push_back(CrossPair{p, pairs[p].i, to, 0});
    }
#pragma omp barrier
  std::vector<std::size_t>& in = cross_in_[b.t].value;
  in.clear();
  for (int u = 0; u < b.t; ++u)
    for (CrossPair& c : cross_out_[u].value)
      if (c.to == b.t) {
        c.at = in.size();  // this entry is written by this thread alone
        in.push_back(c.q);
      }
  cross_forces_[b.t].value.resize(in.size());
}

// After every block's pairs: the forces of the block's cross pairs on their i (computed by the
// blocks of their j), in list order, which for a disc is the order of its j; a recorded pass puts
// their totals in the places the pair stage kept for them.
void World::add_cross_forces(ForceBlock& b) {
  if (b.threads == 1) return;
#pragma omp barrier
  Discs& d = discs;
  PairTotals::Force* const* gap = b.gaps ? b.gaps->data() : nullptr;
  for (const CrossPair& c : cross_out_[b.t].value) {
    const CrossForce& f = cross_forces_[c.to].value[c.at];
    if (!f.touching) continue;
    d.fx[c.i] += f.fx; d.fy[c.i] += f.fy;
    d.torque[c.i] -= f.tq;  // 0 without shear: no change, as the serial pass makes none
    if (gap) **gap++ = PairTotals::Force{f.fn, f.fs};
  }
}

bool World::blocks_fit() const {
  const int n = static_cast<int>(discs.size()), nt = threads_for(n);
  return nt <= 1 ? force_blocks.empty()
                 : force_blocks.size() == static_cast<std::size_t>(nt) + 1 && force_blocks.back() == n;
}

void World::balance_blocks() {
  const int n = static_cast<int>(discs.size());
  const int nt = threads_for(n);
  force_blocks.clear();
  cross_ok_ = false;
  if (nt <= 1) return;
  // Only what a run resumed from a state file has too (its lists are built again at the restart,
  // with other candidates than the run in one piece, but the same history): the discs and the
  // pairs that touched.
  constexpr long kDisc = 1, kTouched = 1;  // relative costs (see force_blocks)
  const auto& pairs = neighbors.pairs;
  const auto work = [](const PairContact& c) { return c.en != 0 || c.es != 0 ? kTouched : 0; };
  long total = kDisc * n;
  for (const PairContact& c : pairs) total += work(c);
  force_blocks.assign(nt + 1, n);
  force_blocks[0] = 0;
  long done = 0;
  std::size_t p = 0;
  int t = 1;
  for (int i = 0; i < n && t < nt; ++i) {
    done += kDisc;
    for (; p < pairs.size() && pairs[p].i <= i; ++p) done += work(pairs[p]);
    while (t < nt && done * nt >= total * t) force_blocks[t++] = i + 1;
  }
}

void World::rebuild_lists() {
  // A few far discs whose candidates are all listed: their references move, the lists stay
  // (Neighbors::patch). Moving walls keep the lists' positions of their own (walls_listed).
  if (moving.empty() && neighbors.patch(discs, geometry)) return;
  // Totals recorded over the old list (a build right after a recorded pass) name their pairs first.
  pair_totals.detach(neighbors.pairs);
  cross_ok_ = false;
  neighbors.rebuild(discs, geometry, threads_for(static_cast<int>(discs.size())));
  if (!moving.empty()) walls_listed();
  if (bonds.empty()) return;
  // Bonded pairs have their own list: drop them from the candidates (both lists sorted by (i, j)).
  auto& p = neighbors.pairs;
  std::size_t o = 0, b = 0;
  for (std::size_t a = 0; a < p.size(); ++a) {
    while (b < bonds.size() && (bonds[b].i < p[a].i || (bonds[b].i == p[a].i && bonds[b].j < p[a].j))) ++b;
    if (b < bonds.size() && bonds[b].i == p[a].i && bonds[b].j == p[a].j) continue;
    p[o++] = p[a];
  }
  p.resize(o);
}

// Gravity, the m_i g of (15a), and a zero torque: the start of the resultants of discs [i0, i1).
void World::start_resultants(int i0, int i1) {
  Discs& d = discs;
  const int* __restrict kd = d.kind.data();
  const double* __restrict km = d.kinds.mass.data();
  double* __restrict fx = d.fx.data(); double* __restrict fy = d.fy.data(); double* __restrict tq = d.torque.data();
  if (one_kind()) {
    const double m = km[0];
    for (int i = i0; i < i1; ++i) {
      fx[i] = m * gx;
      fy[i] = m * gy;
      tq[i] = 0;
    }
    return;
  }
  for (int i = i0; i < i1; ++i) {
    const double m = km[kd[i]];
    fx[i] = m * gx;
    fy[i] = m * gy;
    tq[i] = 0;
  }
}

std::size_t World::touching_pairs(std::size_t p0, std::size_t p1) const {
  const Discs& d = discs;
  const PairContact* pc = neighbors.pairs.data();
  std::size_t n = 0;
  for (std::size_t p = p0; p < p1; ++p) {
    const int i = pc[p].i, j = pc[p].j;
    const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
    n += !apart(dx * dx + dy * dy, d.r(i) + d.r(j));
  }
  return n;
}

}  // namespace dem
