#include "physics/world.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "physics/contact_frame.hpp"
#include "physics/contact_law.hpp"
#include "physics/parallel.hpp"

namespace dem {

// Code compiled for a wider vector than the build's (the kernel table holds each width's): AVX2,
// four doubles a vector, without FMA; AVX-512, eight (512-bit, which GCC otherwise avoids), whose
// FMA is never used for a contraction (-ffp-contract=off).
#define DEM_TARGET_AVX2 __attribute__((target("avx2")))
#define DEM_TARGET_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,prefer-vector-width=512")))

int World::cpu_vector_width() {
#if defined(__x86_64__) && defined(__GNUC__)
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl"))
    return 8;
  if (__builtin_cpu_supports("avx2")) return 4;
#endif
  return 2;
}
const int World::vector_width = World::cpu_vector_width();

void World::set_vector_width(int width) {
  if ((width != 2 && width != 4 && width != 8) || width > vector_width)
    throw std::invalid_argument("set_vector_width: " + std::to_string(width) + " doubles a vector, this processor has " +
                                std::to_string(vector_width));
  width_ = width;
}

int World::threads_for(int n) const {
  const int t = threads_allowed > 0 ? std::min(threads, threads_allowed) : threads;
  return std::max(1, std::min(t, n / kMinDiscsPerThread));
}

struct World::ForceBlock {
  int t = 0, threads = 1;  // this block's thread, of `threads`
  int i0 = 0, i1 = 0;
  std::size_t p0 = 0, p1 = 0, w0 = 0, w1 = 0;
  PairTotals::Force* record = nullptr;     // a recorded pass: this block's first pair total
  std::vector<PairTotals::Force*>* gaps = nullptr;  // a recorded pass with threads: cross pairs' totals (CrossPair)
  double pair_overlap = 0, wall_overlap = 0;  // the largest overlaps (max_overlap)
};

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

// The stages of a force pass and the move, for each block of discs: the row of the kernel table
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

bool World::adjacent(int k1, int k2) const {
  const int nw = static_cast<int>(geometry.walls.size());
  if ((k1 < nw) == (k2 < nw)) return false;
  const int wall = std::min(k1, k2), point = std::max(k1, k2) - nw;
  for (int a : geometry.points[point].adjacent)
    if (a == wall) return true;
  return false;
}

void World::prepare(bool build_lists) {
  if (scheme == Scheme::velocity_verlet_onset &&
      (options.normal_spring != NormalSpring::overlap || !bonds.empty() || !moving.empty()))
    throw std::invalid_argument("velocity_verlet_onset needs the overlap spring, and no bonds or moving walls");
  select_kernel();
  geometry.link_points();
  const int slots = std::max(1, threads);
  touch_scratch_.assign(slots, std::vector<char>(geometry.obstacle_count() + 1, 0));
  dist_scratch_.assign(slots, std::vector<double>(geometry.obstacle_count() + 1, 0.0));
  cross_out_.assign(slots, {});
  cross_in_.assign(slots, {});
  cross_forces_.assign(slots, {});
  cross_gaps_.assign(slots, {});
  cross_ok_ = false;
  touching_.assign(slots, {});
  increment_sums_.assign(slots, {});
  // Only eq. (19) keeps increment arrays (increments()); they start at zero (at rest, or as set).
  Discs& d = discs;
  d.forget_kind_index();  // the discs are in
  for (auto* v : {&d.dux, &d.duy, &d.dphi}) {
    if (scheme != Scheme::paper_eq19) std::vector<double>().swap(*v);
    else v->resize(d.size(), 0.0);
  }
  if (!rotation_angle) std::vector<double>().swap(d.phi);  // an output a scene asks for
  else d.phi.resize(d.size(), 0.0);
  if (!moving.empty()) moving.motion.resize(geometry.obstacle_count());
  // The pairs' kept f_n serve the onset scheme's slip correction under the total cap alone.
  if (scheme != Scheme::velocity_verlet_onset || options.friction_cap != FrictionCap::total) onset_normals.clear();
  if (build_lists) rebuild_lists();  // keeps the history already in the lists
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


void World::drop_pair_forces() {
  pair_totals.clear();
  pair_forces_step = -1;
}

void World::size_pair_forces(std::size_t count) { pair_totals.start(count, neighbors.pairs.size()); }

void World::init() {
  prepare();
  if (scheme == Scheme::velocity_verlet_onset) return onset_forces(true);  // onset.cpp
  forces_then_move(Move::none, 0.0);  // forces at the start (Verlet's first half kick uses them)
}

// The move of the discs: each disc on its own, so any thread count gives the same bits. The kick
// and the drift of a disc go in one pass over the arrays (the same operations, in the same order,
// as a kick pass followed by a drift pass: one sweep of memory instead of two).
namespace {

// The arrays of the move of discs [i0, i1) (World::move_block).
struct MoveArrays {
  int n;
  double h, dt;
  double *fx, *fy, *tq;
  const int* kind;
  const double *inv_mass, *inv_inertia;
  const double* mass;  // RESET: m_i g into fx, fy once read
  double gx, gy;
  double *vx, *vy, *om, *ux, *uy, *up, *x, *y, *phi;
  const float *x0, *y0;  // the skin/2 test: list positions, their origin and the limit
  double ox, oy, lim2;
};

// The loop, with every array a restrict parameter: GCC keeps restrict on parameters, not on
// local pointers; without it, it checked the arrays' overlap at run time, found more pairs to
// check than it will (10), and ran the loop one disc at a time. With it, it runs two discs a
// vector (four with AVX2, eight with AVX-512): the same operations on each disc, the same bits.
// RESET: the forces, once read, set to the next force pass's start (start_resultants: the same
// m_i g, the same bits): one sweep of the force arrays a step less.
// OWED: velocity Verlet's closing half kick of the last step first (World::defer_closing_kick):
// the two kicks one after the other on the same forces, as two sweeps would give them.
template <int D, bool ONE_KIND, bool PHI, bool FAR, bool RESET, bool OWED>  // D: 0 kick alone, 1 eq. (18), 2 eq. (19)
inline __attribute__((always_inline)) long kick_drift_kernel(
    int n, double h, double dt, double* __restrict fx, double* __restrict fy,
    double* __restrict tq, const int* __restrict kd, const double* __restrict im, const double* __restrict ii,
    const double* __restrict km, double gx, double gy,
    double* __restrict vx, double* __restrict vy, double* __restrict om, double* __restrict ux,
    double* __restrict uy, double* __restrict up, double* __restrict x, double* __restrict y,
    double* __restrict phi, const float* __restrict x0, const float* __restrict y0, double ox, double oy,
    double lim2) {
  const double im0 = ONE_KIND ? im[0] : 0, ii0 = ONE_KIND ? ii[0] : 0;  // one kind: its constants, loaded once
  const double gx0 = RESET && ONE_KIND ? km[0] * gx : 0, gy0 = RESET && ONE_KIND ? km[0] * gy : 0;
  long far = 0;
  for (int i = 0; i < n; ++i) {
    const double mi = ONE_KIND ? im0 : im[kd[i]], ji = ONE_KIND ? ii0 : ii[kd[i]];
    const double v0 = OWED ? kick(vx[i], fx[i] * mi, h) : vx[i];  // the owed (17) of the last step
    const double w0 = OWED ? kick(vy[i], fy[i] * mi, h) : vy[i];
    const double o0 = OWED ? kick(om[i], tq[i] * ji, h) : om[i];
    const double v = kick(v0, fx[i] * mi, h);  // (16), (17)
    const double w = kick(w0, fy[i] * mi, h);
    const double o = kick(o0, tq[i] * ji, h);
    vx[i] = v; vy[i] = w; om[i] = o;
    if constexpr (RESET) {  // (15): m_i g, a zero torque
      fx[i] = ONE_KIND ? gx0 : km[kd[i]] * gx;
      fy[i] = ONE_KIND ? gy0 : km[kd[i]] * gy;
      tq[i] = 0;
    }
    if constexpr (D == 0) continue;
    constexpr bool EQ19 = D == 2;
    const double a = move_increment<EQ19>(EQ19 ? ux[i] : 0.0, v, dt);  // (18) or (19)
    const double b = move_increment<EQ19>(EQ19 ? uy[i] : 0.0, w, dt);
    const double c = move_increment<EQ19>(EQ19 ? up[i] : 0.0, o, dt);
    if constexpr (EQ19) { ux[i] = a; uy[i] = b; up[i] = c; }  // (18): v dt, read from v (increments())
    const double xn = x[i] + a, yn = y[i] + b;
    x[i] = xn;
    y[i] = yn;
    if constexpr (PHI) phi[i] += c;
    // The skin/2 test on the position just computed. A count, because an integer sum vectorises
    // and an |= of comparisons does not; a NaN position counts as not far.
    if constexpr (FAR) {
      const double dx = (xn - ox) - x0[i], dy = (yn - oy) - y0[i];
      far += dx * dx + dy * dy > lim2 ? 1 : 0;
    }
  }
  return far;
}

#define DEM_MOVE_ARGS                                                                                           \
  a.n, a.h, a.dt, a.fx, a.fy, a.tq, a.kind, a.inv_mass, a.inv_inertia, a.mass, a.gx, a.gy, a.vx, a.vy, a.om, a.ux, a.uy, a.up, a.x, \
      a.y, a.phi, a.x0, a.y0, a.ox, a.oy, a.lim2
template <int D, bool ONE_KIND, bool PHI, bool FAR, bool RESET, bool OWED>
long move_sse2(const MoveArrays& a) {
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR, RESET, OWED>(DEM_MOVE_ARGS);
}
// Without AVX2 GCC does not vectorise the count of far discs (its floats widen to doubles, the
// count is 64-bit).
#if defined(__x86_64__) && defined(__GNUC__)
template <int D, bool ONE_KIND, bool PHI, bool FAR, bool RESET, bool OWED>
DEM_TARGET_AVX2 long move_avx2(const MoveArrays& a) {
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR, RESET, OWED>(DEM_MOVE_ARGS);
}
template <int D, bool ONE_KIND, bool PHI, bool FAR, bool RESET, bool OWED>
DEM_TARGET_AVX512 long move_avx512(const MoveArrays& a) {
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR, RESET, OWED>(DEM_MOVE_ARGS);
}
#endif
#undef DEM_MOVE_ARGS

// The move kernels (kernels.hpp): kMoves[width index][move], the move numbered
// D * 8 + one kind * 4 + angle * 2 + skin/2 test, D as in kick_drift_kernel, or 3 for eq. (18)
// with the resultants' reset (velocity Verlet's first half step), 4 for that with the owed
// closing kick of the last step before it. A kick alone has neither the angle nor the test (the
// kernel of its row without them).
using MoveKernel = long (*)(const MoveArrays&);
constexpr std::size_t kMoveCount = 40;
template <int W, std::size_t M>
constexpr MoveKernel move_kernel() {
  constexpr int D = M / 8 >= 3 ? 1 : static_cast<int>(M / 8);
  constexpr bool RESET = M / 8 >= 3, OWED = M / 8 == 4;
  constexpr bool ONE_KIND = M / 4 % 2 == 1, PHI = D != 0 && M / 2 % 2 == 1, FAR = D != 0 && M % 2 == 1;
#if defined(__x86_64__) && defined(__GNUC__)
  if constexpr (W == 8) return &move_avx512<D, ONE_KIND, PHI, FAR, RESET, OWED>;
  else if constexpr (W == 4) return &move_avx2<D, ONE_KIND, PHI, FAR, RESET, OWED>;
  else
#endif
  return &move_sse2<D, ONE_KIND, PHI, FAR, RESET, OWED>;
}
template <int W, std::size_t... M>
constexpr std::array<MoveKernel, kMoveCount> move_kernels(std::index_sequence<M...>) {
  return {move_kernel<W, M>()...};
}
constexpr std::array<MoveKernel, kMoveCount> kMoves[3] = {move_kernels<2>(std::make_index_sequence<kMoveCount>{}),
                                                          move_kernels<4>(std::make_index_sequence<kMoveCount>{}),
                                                          move_kernels<8>(std::make_index_sequence<kMoveCount>{})};

}  // namespace

// (16)-(19) for discs [i0, i1): whether some disc of them is now more than skin/2 from its list
// position (or the lists are stale). A kick alone (Verlet's closing half) moves nothing.
bool World::move_block(Move move, double h, int i0, int i1, bool reset, bool owed) {
  if (move == Move::none) return false;
  Discs& d = discs;
  const int D = move == Move::kick ? 0 : move == Move::kick_drift_eq18 ? 1 : 2;
  // Stale lists (a restart, a wall removed): rebuilt before the next forces, nothing to test.
  const bool stale = D != 0 && neighbors.stale(d);
  const bool test = D != 0 && !stale;
  const auto at = [i0](auto& v) { return v.empty() ? nullptr : v.data() + i0; };  // eq. 19's and the angle's may be empty
  reset = reset && D == 1;
  owed = owed && reset;  // only velocity Verlet's first sweep gives an owed kick
  const MoveArrays a{i1 - i0, h, dt, at(d.fx), at(d.fy), at(d.torque), at(d.kind), d.kinds.inv_mass.data(),
                     d.kinds.inv_inertia.data(), d.kinds.mass.data(), gx, gy, at(d.vx), at(d.vy), at(d.omega), at(d.dux), at(d.duy), at(d.dphi),
                     at(d.x), at(d.y), at(d.phi), test ? neighbors.reference_x().data() + i0 : nullptr,
                     test ? neighbors.reference_y().data() + i0 : nullptr, neighbors.origin_x(),
                     neighbors.origin_y(), neighbors.moved_far_limit2()};
  const std::size_t m = (owed ? 4 : reset ? 3 : D) * 8 + (one_kind() ? 4 : 0) + (d.phi.empty() ? 0 : 2) + (test ? 1 : 0);
  const long far = kMoves[width_index()][m](a);
  return stale || far != 0;
}

// One parallel region: each thread an equal block of discs (block_start; the force pass balances
// its blocks by work, force_blocks: here every disc costs the same).
bool World::move_discs(Move move, double h, bool reset, bool owed) {
  const int n = static_cast<int>(discs.size());
  const int nt = threads_for(n);
  if (nt <= 1) return move_block(move, h, 0, n, reset, owed);
  unsigned far = 0;
#pragma omp parallel num_threads(nt) reduction(| : far)
  {
    const int t = omp_thread_index();
    far |= move_block(move, h, block_start(n, nt, t), block_start(n, nt, t + 1), reset, owed) ? 1u : 0u;
  }
  return far != 0;
}

void World::pay_kick() {
  if (!kick_owed_) return;
  kick_owed_ = false;
  move_discs(Move::kick, owed_h_);
}

void World::velocity_now(std::size_t i, double& vx, double& vy) const {
  vx = discs.vx[i];
  vy = discs.vy[i];
  if (!kick_owed_) return;
  const double mi = discs.inv_mass(i);  // the kernel's operations (kick_drift_kernel): kick(v, f / m, h)
  vx = kick(vx, discs.fx[i] * mi, owed_h_);
  vy = kick(vy, discs.fy[i] * mi, owed_h_);
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

// The law for n touching pairs of a block, in the block's arrays (pair_contacts): no branch and no
// store that a later pair reads, so the compiler runs it two pairs at a time (SSE2) and the
// pairs' square roots and divisions overlap. The same operations, in the same order, as the
// law applied pair by pair: the same bits. One kind of disc: r_i + r_j is `sum1` (not gathered
// pair by pair). `uf`: the factor of the stored increments (World::increments: dt for eq. 18 and
// Verlet, which store v), applied here a vector at a time rather than in the gather.
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
static inline __attribute__((always_inline)) void pair_block_law(PairBlock& b, int n, const PairProps* __restrict props,
                                                                 double inv_dt, double sum1, double uf) {
  for (int k = 0; k < n; ++k) {
    const double R = std::sqrt(b.R2[k]);
    const UnitNormal nrm = unit_normal(b.dx[k], b.dy[k], R);  // (4)
    const double ddx = b.dui[k] * uf - b.duj[k] * uf, ddy = b.dvi[k] * uf - b.dvj[k] * uf;  // du_i - du_j of (5)
    const double du_n = normal_increment(ddx, ddy, nrm);       // (5a)
    const double overlap = (ONE_KIND ? sum1 : b.sum[k]) - R;
    double du_s = 0;
    if constexpr (SHEAR && LA == LeverArm::contact_point) {
      // (5b) with the arms r - overlap/2 (one kind: sum1 / 2 is r exactly)
      const double ai = (ONE_KIND ? 0.5 * sum1 : b.arm_i[k]) - 0.5 * overlap;
      const double aj = (ONE_KIND ? 0.5 * sum1 : b.arm_j[k]) - 0.5 * overlap;
      du_s = shear_increment(ddx, ddy, nrm, ai * (b.rot_i[k] * uf), aj * (b.rot_j[k] * uf));
      b.arm_i[k] = ai; b.arm_j[k] = aj;
    } else if constexpr (SHEAR) {
      const double ri = ONE_KIND ? 0.5 * sum1 : b.arm_i[k], rj = ONE_KIND ? 0.5 * sum1 : b.arm_j[k];
      du_s = shear_increment(ddx, ddy, nrm, ri * (b.rot_i[k] * uf), rj * (b.rot_j[k] * uf));  // (5b): r dphi
    }
    double fn, fs;
    contact_law<NS, NT, FC, SHEAR, DASH>(props[ONE_KIND ? 0 : b.prop[k]], overlap, du_n, du_s, inv_dt, b.en[k],
                                         b.es[k], fn, fs);
    const ContactForce f = contact_force<SHEAR>(fn, fs, nrm);  // (15a), (15b): on i
    b.overlap[k] = overlap;  // (a max taken here instead would keep GCC, without -ffast-math, from vectorising the loop)
    b.fn[k] = fn; b.fs[k] = fs;
    b.fx[k] = f.x; b.fy[k] = f.y;
  }
}

// The block's law compiled three times: for any x86-64 (two pairs a vector), for AVX2 (four) and
// for AVX-512 (eight); the kernel table holds all three, a world runs its width's. IEEE
// operations give the same bits at any width, and no contraction into FMA (-ffp-contract=off,
// and the AVX2 version does not enable FMA).
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
static void pair_block_law_sse2(PairBlock& b, int n, const PairProps* __restrict props, double inv_dt, double sum1,
                                double uf) {
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1, uf);
}
#if defined(__x86_64__) && defined(__GNUC__)
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
DEM_TARGET_AVX2 static void pair_block_law_avx2(PairBlock& b, int n, const PairProps* __restrict props, double inv_dt,
                                                double sum1, double uf) {
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1, uf);
}
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
DEM_TARGET_AVX512 static void pair_block_law_avx512(PairBlock& b, int n, const PairProps* __restrict props,
                                                    double inv_dt, double sum1, double uf) {
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1, uf);
}
#endif
// The block law at W doubles a vector (a row of the kernel table holds each width's). A
// sanitizer build (DEM_LAW_ONE_WIDTH, -O1: no vector code at any width) compiles it once, for
// every width: the three would be the same scalar code there, and a third of this file's
// compile time.
template <int W, NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
constexpr auto pair_block_law_at() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(DEM_LAW_ONE_WIDTH)
  if constexpr (W == 8) return &pair_block_law_avx512<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>;
  else if constexpr (W == 4) return &pair_block_law_avx2<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>;
  else
#endif
  return &pair_block_law_sse2<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>;
}

namespace {
// A recorded pass's totals (World::pair_contacts): written in list order from `at` on, and each
// pair's bit gathered a word at a time and or-ed into the list's bits (a thread's first and last
// words may be shared with its neighbours': atomic, in any order).
struct TotalsWriter {
  PairTotals::Force* at;
  std::uint64_t* bits;
  std::size_t word = 0;
  std::uint64_t word_bits = 0;
  void put(std::size_t q, double fn, double fs) {  // pair q's totals and bit
    *at++ = PairTotals::Force{fn, fs};
    if ((q >> 6) != word) {
      flush();
      word = q >> 6;
      word_bits = 0;
    }
    word_bits |= std::uint64_t{1} << (q & 63);
  }
  // Places for the touching cross pairs gap[g], ... (list offsets from p0) before offset `below`:
  // kept in `places`, filled by add_cross_forces once j's block has computed them (a pointer: a
  // pass without threads has no cross pairs, count 0, and no places).
  void keep(const int* gap, int count, int& g, std::size_t p0, std::size_t below, std::vector<PairTotals::Force*>* places) {
    for (; g < count && static_cast<std::size_t>(gap[g]) < below; ++g) {
      places->push_back(at);
      put(p0 + static_cast<std::size_t>(gap[g]), 0, 0);
    }
  }
  void flush() {
    if (word_bits != 0) __atomic_fetch_or(&bits[word], word_bits, __ATOMIC_RELAXED);
  }
};
}  // namespace

// A pair stage's arrays (World::pair_contacts) and its two sub-steps around the law: gather a
// block of touching pairs from the list, add the block's forces to the discs. Inlined into the
// stage: one loop, as if written there.
template <LeverArm LA, bool SHEAR, bool RECORD, bool ONE_KIND, bool CROSS>
struct World::PairPass {
  ForceBlock& blk;
  const std::size_t* cross;  // CROSS: the block's cross pairs (cross_in_), and their results
  CrossForce* cross_f;
  std::size_t p0, p1;
  PairContact* pc;
  const Discs& d;
  const double *x, *y;
  // Radius and material by kind: a small table, read through each disc's kind.
  const int* kd;
  const double* kr;
  const int* kmat;
  Increments u;
  double *fxa, *fya, *tq;
  int n_mat;
  double sum1;  // r_i + r_j of every pair, one kind of disc
  double lim1;  // apart() of one kind of disc: R^2 > lim1, its square taken once

  PairPass(World& w, ForceBlock& b)
      : blk(b),
        cross(CROSS ? w.cross_in_[b.t].value.data() : nullptr),
        cross_f(CROSS ? w.cross_forces_[b.t].value.data() : nullptr),
        p0(CROSS ? 0 : b.p0),
        p1(CROSS ? w.cross_in_[b.t].value.size() : b.p1),
        pc(w.neighbors.pairs.data()),
        d(w.discs),
        x(d.x.data()),
        y(d.y.data()),
        kd(d.kind.data()),
        kr(d.kinds.r.data()),
        kmat(d.kinds.material.data()),
        u(w.increments()),
        fxa(w.discs.fx.data()),
        fya(w.discs.fy.data()),
        tq(w.discs.torque.data()),
        n_mat(w.n_materials),
        sum1(ONE_KIND ? kr[0] + kr[0] : 0.0),
        lim1(sum1 * sum1) {}

  PairContact& contact(std::size_t p) const { return pc[CROSS ? cross[p] : p]; }

  // Pairs from p on into the block b (n of them so far), up to the next cross pair `stop` or a
  // full block. A pair found apart loses its history here (3).
  __attribute__((always_inline)) void gather(PairBlock& b, int& n, std::size_t& p, std::size_t stop) const {
    PairContact* __restrict pcr = pc;
    const double* __restrict xr = x; const double* __restrict yr = y;
    const int* __restrict kdr = kd; const double* __restrict krr = kr; const int* __restrict kmr = kmat;
    const double* __restrict ux = u.x; const double* __restrict uy = u.y; const double* __restrict uphi = u.phi;
    // One bound, so that the loop tests one index.
    const std::size_t end = std::min(stop, p + static_cast<std::size_t>(PairBlock::kSize - n));
    for (; p < end; ++p) {
      PairContact& c = pcr[CROSS ? cross[p] : p];
      const int i = c.i, j = c.j;
      const int ki = ONE_KIND ? 0 : kdr[i], kj = ONE_KIND ? 0 : kdr[j];
      const double ri = krr[ki], rj = krr[kj];
      const double dx = xr[j] - xr[i], dy = yr[j] - yr[i];
      const double R2 = dx * dx + dy * dy, sum = ri + rj;
      if (ONE_KIND ? R2 > lim1 : apart(R2, sum)) {  // (3): apart; the contact and its history end
        c.en = c.es = 0;
        if constexpr (CROSS) cross_f[p].touching = false;
        continue;
      }
      b.pair[n] = static_cast<int>(p - p0);
      b.dx[n] = dx; b.dy[n] = dy; b.R2[n] = R2;
      if constexpr (!ONE_KIND) b.sum[n] = sum;
      b.dui[n] = ux[i]; b.duj[n] = ux[j];  // (5), times uf in the law
      b.dvi[n] = uy[i]; b.dvj[n] = uy[j];
      if constexpr (SHEAR) {  // r dphi of (5b) in the law (the contact point's arms need the overlap)
        b.rot_i[n] = uphi[i];
        b.rot_j[n] = uphi[j];
        if constexpr (!ONE_KIND) { b.arm_i[n] = ri; b.arm_j[n] = rj; }
      }
      if constexpr (!ONE_KIND) b.prop[n] = kmr[ki] * n_mat + kmr[kj];
      b.en[n] = c.en; b.es[n] = c.es;
      ++n;
    }
  }

  // The law's results of the block's n pairs to the discs, in list order, the sums of (15); the
  // history back to the list. RECORD: the totals (and the places of the touching cross pairs
  // before offset `below`, b.gap[0, gaps)). CROSS: the force on j added, the one on i kept for
  // i's block (add_cross_forces).
  __attribute__((always_inline)) void add(const PairBlock& b, int n, int gaps, std::size_t below, TotalsWriter& totals,
                                          double& worst) const {
    const int* __restrict kdr = kd; const double* __restrict krr = kr;
    double* __restrict fx_ = fxa; double* __restrict fy_ = fya; double* __restrict tq_ = tq;
    // Disc i's sums in registers while its pairs follow one another (the list is sorted by i; a j
    // is never the current i): the same additions in the same order, without a store and a
    // reload of fx[i], fy[i], torque[i] between two pairs of one disc.
    int cur = -1;
    double ax = 0, ay = 0, at = 0;
    const auto put_back = [&] {  // the current disc's sums to its arrays
      if (cur < 0) return;
      fx_[cur] = ax; fy_[cur] = ay;
      if constexpr (SHEAR) tq_[cur] = at;
    };
    int g = 0;  // RECORD: the next cross pair's place to keep
    for (int k = 0; k < n; ++k) {
      PairContact& c = pc[CROSS ? cross[b.pair[k]] : p0 + static_cast<std::size_t>(b.pair[k])];
      const int i = c.i, j = c.j;
      c.en = b.en[k]; c.es = b.es[k];
      worst = std::max(worst, b.overlap[k]);
      const double fx = b.fx[k], fy = b.fy[k], fs = b.fs[k];
      constexpr bool CP = LA == LeverArm::contact_point;
      const double rj = CP ? b.arm_j[k] : krr[ONE_KIND ? 0 : kdr[j]];
      if constexpr (CROSS) {  // j is this block's; i's forces go to its block
        const double ri = CP ? b.arm_i[k] : krr[ONE_KIND ? 0 : kdr[i]];
        cross_f[b.pair[k]] = CrossForce{fx, fy, SHEAR ? contact_moment(ri, fs) : 0.0, b.fn[k], fs, true};
        fx_[j] -= fx; fy_[j] -= fy;
        if constexpr (SHEAR) tq_[j] -= contact_moment(rj, fs);
        continue;
      }
      if constexpr (RECORD) {
        totals.keep(b.gap, gaps, g, p0, static_cast<std::size_t>(b.pair[k]), blk.gaps);
        totals.put(p0 + static_cast<std::size_t>(b.pair[k]), b.fn[k], fs);
      }
      if (i != cur) {
        put_back();
        cur = i;
        ax = fx_[i]; ay = fy_[i];
        if constexpr (SHEAR) at = tq_[i];
      }
      ax += fx; ay += fy;
      if constexpr (SHEAR) at -= contact_moment(CP ? b.arm_i[k] : krr[ONE_KIND ? 0 : kdr[i]], fs);  // (15c)
      fx_[j] -= fx; fy_[j] -= fy;
      if constexpr (SHEAR) tq_[j] -= contact_moment(rj, fs);
    }
    put_back();
    if constexpr (RECORD) totals.keep(b.gap, gaps, g, p0, below, blk.gaps);
  }
};

// The stage of the disc pairs: the block's pairs [p0, p1) of the sorted list, a block of touching
// pairs at a time. The geometry of each pair is gathered (a pair found apart loses its history
// there), the law runs on the block's arrays (pair_block_law: (4), (5), (6)-(14), (15a, b)), and
// the results are added to the discs in list order, the sums of (15). A pair whose j is in a
// later block (a cross pair) is left to j's block. RECORD: the totals of the touching pairs are
// written in list order from the block's `record` on (TotalsWriter), a touching cross pair's
// place kept in `gaps`. CROSS: the block's cross pairs (cross_in_): the force on j added, the one
// on i kept for i's block (add_cross_forces).
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool RECORD, bool ONE_KIND,
          bool CROSS>
void World::pair_contacts(ForceBlock& blk) {
  static_assert(!(CROSS && RECORD), "the cross pass hands its totals to i's block");
  const PairPass<LA, SHEAR, RECORD, ONE_KIND, CROSS> pass(*this, blk);
  const std::size_t p0 = pass.p0, p1 = pass.p1;
  const PairLaw law = kernel_->pair_law[width_index()][ONE_KIND];
  const double inv_dt = 1.0 / dt;
  // One kind of disc: one pair of materials, its constants fetched once.
  const PairProps* law_props = ONE_KIND ? &props[pass.kmat[0] * n_materials + pass.kmat[0]] : props.data();
  PairBlock b;  // on this thread's stack (20 kB), hot in its cache
  double worst = 0;
  TotalsWriter totals{blk.record, RECORD ? pair_totals.bits() : nullptr};  // RECORD only
  // The own pass stops at each of the block's cross pairs (cross_out_, in list order) and skips it:
  // j's block computes it. Between them, and on one thread, the loop tests nothing more.
  const CrossPair* next_cross = CROSS || blk.threads == 1 ? nullptr : cross_out_[blk.t].value.data();
  const CrossPair* const cross_end = next_cross ? next_cross + cross_out_[blk.t].value.size() : nullptr;
  std::size_t stop = next_cross != cross_end ? next_cross->q : p1;
  for (std::size_t p = p0; p < p1;) {
    int n = 0, gaps = 0;
    while (p < p1 && n < PairBlock::kSize && gaps < PairBlock::kSize) {
      if (p == stop) {  // a cross pair
        if constexpr (RECORD) {
          const PairContact& c = pass.contact(p);
          const double dx = pass.x[c.j] - pass.x[c.i], dy = pass.y[c.j] - pass.y[c.i];
          if (!apart(dx * dx + dy * dy, discs.r(c.i) + discs.r(c.j))) b.gap[gaps++] = static_cast<int>(p - p0);
        }
        ++p;
        stop = ++next_cross != cross_end ? next_cross->q : p1;
        continue;
      }
      pass.gather(b, n, p, stop);
    }
    law(b, n, law_props, inv_dt, pass.sum1, pass.u.factor);
    pass.add(b, n, gaps, p - p0, totals, worst);
  }
  if constexpr (RECORD) totals.flush();
  blk.pair_overlap = std::max(blk.pair_overlap, worst);
}

// The stage of the discs on walls and points: the block's entries [w0, w1) of the wall list
// (whole groups of one disc), with its thread's scratch. MOVING: the obstacles' motion enters
// (5), and the reactions on them are summed for the plates' move.
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool MOVING, bool SHEAR, bool DASH>
void World::wall_contacts(ForceBlock& blk) {
  const std::size_t w0 = blk.w0, w1 = blk.w1;
  const int slot = blk.t;
  if constexpr (MOVING)  // one block (forces_then_move): every obstacle's sums start here
    for (ObstacleMotion& m : moving.motion) m.fx = m.fy = m.moment = 0;
  Discs& d = discs;
  const double inv_dt = 1.0 / dt;
  double worst = 0;
  // Walls and points: the same law with a fixed partner of zero radius.
  auto& wl = neighbors.walls;
  const std::size_t nw = w1;
  const int n_walls = static_cast<int>(geometry.walls.size());
  const int n_mat = n_materials;
  const Increments u = increments();
  for (std::size_t b = w0; b < nw;) {
    std::size_t e = b;
    while (e < nw && wl[e].i == wl[b].i) ++e;  // the entries of one disc: [b, e)
    const int i = wl[b].i;
    // Geometry first, so that a contact passing from a wall to its end point keeps its history
    // (the normal is continuous there; the paper is silent, a reset would kick the disc).
    char* now = touch_scratch_[slot].data();
    double* dist_scratch = dist_scratch_[slot].data();
    for (std::size_t a = b; a < e; ++a) {
      WallContact& c = wl[a];
      ObstacleHit h{};
      now[a - b] = closest_point(geometry, c.k, d.x[i], d.y[i], h) && h.dist <= d.r(i) && h.dist > 0;
      if (now[a - b]) {
        dist_scratch[a - b] = h.dist;
        c.px = h.px; c.py = h.py;
        const UnitNormal nrm = unit_normal(h.px - d.x[i], h.py - d.y[i], h.dist);  // (4), j the obstacle
        c.nx = nrm.x;
        c.ny = nrm.y;
      }
    }
    for (std::size_t a = b; a < e; ++a) {
      if (!now[a - b] || wl[a].touching) continue;
      for (std::size_t o = b; o < e; ++o)  // a new contact inherits from a lost neighbour
        if (!now[o - b] && wl[o].touching && adjacent(wl[o].k, wl[a].k)) {
          wl[a].en = wl[o].en; wl[a].es = wl[o].es;
          wl[o].en = wl[o].es = 0;
        }
    }
    for (std::size_t a = b; a < e; ++a) {
      WallContact& c = wl[a];
      c.touching = now[a - b];
      if (!c.touching) { c.en = c.es = c.fn = c.fs = 0; continue; }
      const double dist = dist_scratch[a - b];
      const UnitNormal nrm{c.nx, c.ny};
      const double overlap = d.r(i) - dist;
      // The lever arm of (5b), (15c): r, or r - overlap/2 (the middle of the overlap). A moving
      // wall's own point stays the closest point (px, py) of its surface.
      const double arm = LA == LeverArm::contact_point ? d.r(i) - 0.5 * overlap : d.r(i);
      double ddx = u.x[i] * u.factor, ddy = u.y[i] * u.factor;  // du_i - du_j of (5), j the obstacle:
      if constexpr (MOVING) {  // a moving one's material point at the contact moved too
        const ObstacleMotion& m = moving.motion[c.k];
        ddx -= m.dux - m.dtheta * (c.py - m.pivot_y);
        ddy -= m.duy + m.dtheta * (c.px - m.pivot_x);
      }
      const double du_n = normal_increment(ddx, ddy, nrm);                            // (5a)
      const double du_s = shear_increment(ddx, ddy, nrm, arm * (u.phi[i] * u.factor));  // (5b)
      worst = std::max(worst, overlap);
      const int km = c.k < n_walls ? geometry.walls[c.k].material
                                   : geometry.points[c.k - n_walls].material;
      contact_law<NS, NT, FC, SHEAR, DASH>(props[d.material(i) * n_mat + km], overlap, du_n, du_s, inv_dt,
                                           c.en, c.es, c.fn, c.fs);
      const ContactForce f = contact_force(c.fn, c.fs, nrm);  // (15)
      d.fx[i] += f.x;
      d.fy[i] += f.y;
      d.torque[i] -= contact_moment(arm, c.fs);
      if constexpr (MOVING) {  // the reaction on the obstacle: (15) of the opposite forces
        ObstacleMotion& m = moving.motion[c.k];
        const ContactForce w = contact_force(-c.fn, -c.fs, nrm);
        m.fx += w.x;
        m.fy += w.y;
        m.moment += (c.px - m.pivot_x) * w.y - (c.py - m.pivot_y) * w.x;
      }
    }
    b = e;
  }
  blk.wall_overlap = worst;
}

// The stage of paper 2's bonds (one block of all discs: forces_then_move): each bond is a pair
// of the law without its two conditions (bond_law), whatever the discs' distance.
template <NormalSpring NS>
void World::bond_contacts(ForceBlock& blk) {
  Discs& d = discs;
  const double inv_dt = 1.0 / dt;
  const Increments u = increments();
  for (Bond& b : bonds) {
    const int i = b.i, j = b.j;
    const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
    const double R = std::sqrt(dx * dx + dy * dy);
    const UnitNormal nrm = unit_normal(dx, dy, R);  // (4)
    const double ddx = u.x[i] * u.factor - u.x[j] * u.factor, ddy = u.y[i] * u.factor - u.y[j] * u.factor;
    const double du_n = normal_increment(ddx, ddy, nrm);  // (5a)
    const double du_s = shear_increment(ddx, ddy, nrm, b.ai * (u.phi[i] * u.factor), b.aj * (u.phi[j] * u.factor));  // (5b)
    bond_law<NS>(pair(d.material(i), d.material(j)), b.rest - R, du_n, du_s, inv_dt, b.en, b.es, b.fn, b.fs);
    blk.pair_overlap = std::max(blk.pair_overlap, d.r(i) + d.r(j) - R);
    const ContactForce f = contact_force(b.fn, b.fs, nrm);  // (15)
    d.fx[i] += f.x; d.fy[i] += f.y;
    d.fx[j] -= f.x; d.fy[j] -= f.y;
    d.torque[i] -= contact_moment(b.ai, b.fs);
    d.torque[j] -= contact_moment(b.aj, b.fs);
  }
}


// Row K of the kernel table (kernels.hpp): the stages of its law and features, and its pair law
// at each vector width.
template <std::size_t K>
World::Kernel World::make_kernel() {
  constexpr KernelKey key = kernel_key(K);
  constexpr NormalSpring NS = key.law.normal_spring;
  constexpr NoTension NT = key.law.no_tension;
  constexpr FrictionCap FC = key.law.friction_cap;
  constexpr LeverArm LA = key.features.lever_arm;
  constexpr bool S = key.features.shear, D = key.features.dashpots, M = key.features.moving_walls;
  Kernel k;
  k.key = key;
  k.name = dem::kernel_name(key);
  k.pairs[0][0] = &World::pair_contacts<NS, NT, FC, LA, S, D, false, false>;
  k.pairs[0][1] = &World::pair_contacts<NS, NT, FC, LA, S, D, false, true>;
  k.pairs[1][0] = &World::pair_contacts<NS, NT, FC, LA, S, D, true, false>;
  k.pairs[1][1] = &World::pair_contacts<NS, NT, FC, LA, S, D, true, true>;
  k.cross[0] = &World::pair_contacts<NS, NT, FC, LA, S, D, false, false, true>;
  k.cross[1] = &World::pair_contacts<NS, NT, FC, LA, S, D, false, true, true>;
  k.walls = &World::wall_contacts<NS, NT, FC, LA, M, S, D>;
  if constexpr (key.features.bonds) k.bonds = &World::bond_contacts<NS>;
  k.pair_law[0][0] = pair_block_law_at<2, NS, NT, FC, LA, S, D, false>();
  k.pair_law[0][1] = pair_block_law_at<2, NS, NT, FC, LA, S, D, true>();
  k.pair_law[1][0] = pair_block_law_at<4, NS, NT, FC, LA, S, D, false>();
  k.pair_law[1][1] = pair_block_law_at<4, NS, NT, FC, LA, S, D, true>();
  k.pair_law[2][0] = pair_block_law_at<8, NS, NT, FC, LA, S, D, false>();
  k.pair_law[2][1] = pair_block_law_at<8, NS, NT, FC, LA, S, D, true>();
  return k;
}

namespace {
template <class Kernel, class Make, std::size_t... K>
std::vector<Kernel> make_table(Make make, std::index_sequence<K...>) {
  return {make(std::integral_constant<std::size_t, K>{})...};
}
}  // namespace

const std::vector<World::Kernel>& World::kernels() {
  static const std::vector<Kernel> table = make_table<Kernel>(
      [](auto k) { return make_kernel<decltype(k)::value>(); }, std::make_index_sequence<kKernelCount>{});
  return table;
}

std::vector<std::string> World::kernel_names() {
  std::vector<std::string> names;
  for (const Kernel& k : kernels()) names.push_back(k.name);
  return names;
}

const std::string& World::kernel_name() const {
  static const std::string none = "none (prepare() selects it)";
  return kernel_ ? kernel_->name : none;
}

std::string kernel_name(const KernelKey& key) {
  const Law& l = key.law;
  const Features& f = key.features;
  std::string s = std::string(to_string(l.normal_spring)) + "/" + to_string(l.no_tension) + "/" + to_string(l.friction_cap) +
                  " " + to_string(f.lever_arm);
  if (f.shear) s += " shear";
  if (f.dashpots) s += " dashpots";
  if (f.bonds) s += " bonds";
  if (f.moving_walls) s += " moving_walls";
  return s;
}

// The one dispatcher: the row of the table for this scene's law and what it uses.
void World::select_kernel() {
  const bool has_bonds = !bonds.empty(), has_moving = !moving.empty();
  bool shear = false, dash = false;
  for (const PairProps& p : props) {
    const bool shear_free = (p.ks == 0 && p.eta_s == 0) || (p.mu == 0 && p.ks > 0);  // cap 0 holds e_s = 0
    shear = shear || !shear_free;
    dash = dash || p.eta_n != 0 || p.eta_s != 0;
  }
  if (has_bonds || has_moving) shear = dash = true;  // as the table compiles them
  kernel_shear = shear;
  kernel_dashpots = dash;
  // The lever arm matters only where there is shear: a shear-free scene runs the radius kernel
  // (the same result).
  const LeverArm lever = shear ? options.lever_arm : LeverArm::radius;
  const KernelKey want{{options.normal_spring, options.no_tension, options.friction_cap},
                       {lever, shear, dash, has_bonds, has_moving}};
  for (const Kernel& k : kernels())
    if (k.key == want) {
      kernel_ = &k;
      return;
    }
  throw std::logic_error("no compiled kernel for " + dem::kernel_name(want));
}

void World::remove_discs(const RemovedDiscs& removed) {
  Discs& d = discs;
  const std::size_t n = d.size();
  const std::vector<int>& gone = removed.sorted;
  for (std::size_t k = 0; k < gone.size(); ++k)
    if (gone[k] < 0 || static_cast<std::size_t>(gone[k]) >= n || (k > 0 && gone[k] <= gone[k - 1]))
      throw std::logic_error("remove_discs: the removed indices are not sorted, distinct discs");
  if (gone.empty()) return;
  auto keep = [&](auto& v) { removed.compact(v); };
  d.make_ids();  // the first removal: ids are no longer the indices
  keep(d.kind); keep(d.id);  // the kinds table stays (a kind without discs costs its entry only)
  keep(d.x); keep(d.y); keep(d.vx); keep(d.vy); keep(d.omega);
  if (!d.phi.empty()) keep(d.phi);  // output.rotation_angle only
  if (!d.dux.empty()) { keep(d.dux); keep(d.duy); keep(d.dphi); }  // eq. 19 only
  keep(d.fx); keep(d.fy); keep(d.torque);
  pair_totals.compact(neighbors.pairs, removed);  // the recorded totals follow their pairs
  onset_normals.compact(removed);  // and the onset scheme's f_n (history)
  neighbors.compact(removed);
  cross_ok_ = false;
  for (int& b : force_blocks)  // the same block edges, less the discs gone below them
    b -= static_cast<int>(std::lower_bound(gone.begin(), gone.end(), b) - gone.begin());
  if (!bonds.empty()) {  // a bond goes with either of its discs; order (i, j) is kept
    std::size_t k = 0;
    for (const Bond& b : bonds) {
      const int i = removed.new_index(b.i), j = removed.new_index(b.j);
      if (i < 0 || j < 0) continue;
      Bond q = b;
      q.i = i;
      q.j = j;
      bonds[k++] = q;
    }
    bonds.resize(k);
    select_kernel();
  }
}

bool World::deactivate_wall(const std::string& name) {
  for (Wall& w : geometry.walls)
    if (w.name == name && w.active) {
      w.active = false;
      geometry.link_points();  // the slit ends now act as points
      neighbors.invalidate();
      return true;
    }
  return false;
}

World::Increments World::increments() const {
  const Discs& d = discs;
  if (scheme == Scheme::paper_eq19) return {d.dux.data(), d.duy.data(), d.dphi.data(), 1.0};
  return {d.vx.data(), d.vy.data(), d.omega.data(), dt};
}

// The sums of parallel_sum (its blocks of kSumBlock discs, each summed in order): the same bits
// as summing stored increments with it, whatever the thread count.
void World::measure_increment_sums() {
  const long n = static_cast<long>(discs.size());
  const long nb = sum_blocks(n);
  increment_sums_.resize(static_cast<std::size_t>(nb));
  const double* vx = discs.vx.data(); const double* vy = discs.vy.data();
  parallel_for(nb, static_cast<int>(std::min<long>(threads_for(static_cast<int>(n)), nb)), [&](long b) {
    double sx = 0, sy = 0;
    for (long i = b * kSumBlock, end = std::min(n, (b + 1) * kSumBlock); i < end; ++i) {
      sx += std::abs(vx[i] * dt);
      sy += std::abs(vy[i] * dt);
    }
    increment_sums_[static_cast<std::size_t>(b)].value = {sx, sy};
  });
}

void World::mean_abs_increment(double& mx, double& my) const {
  const long n = static_cast<long>(discs.size());
  const int nt = threads_for(static_cast<int>(n));
  if (verlet_family(scheme)) {
    if (increments_measured_step_ != steps)
      throw std::logic_error("mean_abs_increment: this Verlet step did not measure its increments");
    mx = my = 0;
    for (long b = 0; b < sum_blocks(n); ++b) { mx += increment_sums_[b].value[0]; my += increment_sums_[b].value[1]; }
  } else {
    const Increments u = increments();
    mx = parallel_sum(n, nt, [&](long i) { return std::abs(u.x[i] * u.factor); });
    my = parallel_sum(n, nt, [&](long i) { return std::abs(u.y[i] * u.factor); });
  }
  if (n) { mx /= static_cast<double>(n); my /= static_cast<double>(n); }
}

void World::require_velocities(const char* who) const {
  if (kick_owed_) throw std::logic_error(std::string(who) + ": the velocities are read while velocity Verlet's closing half kick is owed (pay_kick first)");
}

double World::kinetic_energy() const {
  require_velocities("kinetic_energy");
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return parallel_sum(n, threads_for(static_cast<int>(n)), [&](long i) {
    return 0.5 * d.mass(i) * (d.vx[i] * d.vx[i] + d.vy[i] * d.vy[i]) +
           0.5 / d.inv_inertia(i) * d.omega[i] * d.omega[i];
  });
}

bool World::all_finite() const {
  require_velocities("all_finite");
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return !parallel_any(n, threads_for(static_cast<int>(n)), [&](long i) {
    return !std::isfinite(d.x[i]) || !std::isfinite(d.y[i]) || !std::isfinite(d.vx[i]) ||
           !std::isfinite(d.vy[i]) || !std::isfinite(d.omega[i]);
  });
}

const char* to_string(NormalSpring v) { return v == NormalSpring::incremental ? "incremental" : "overlap"; }
const char* to_string(NoTension v) {
  return v == NoTension::elastic ? "elastic" : v == NoTension::total ? "total" : v == NoTension::overlap ? "overlap" : "none";
}
const char* to_string(FrictionCap v) {
  return v == FrictionCap::elastic ? "elastic" : v == FrictionCap::total ? "total" : "none";
}
const char* to_string(LeverArm v) { return v == LeverArm::radius ? "radius" : "contact_point"; }
const char* to_string(Scheme v) {
  return v == Scheme::paper_eq18 ? "paper_eq18" : v == Scheme::paper_eq19 ? "paper_eq19"
       : v == Scheme::velocity_verlet ? "velocity_verlet" : "velocity_verlet_onset";
}

}  // namespace dem
