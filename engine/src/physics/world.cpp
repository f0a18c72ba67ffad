#include "physics/world.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "physics/contact_law.hpp"
#include "physics/parallel.hpp"

namespace dem {

// Code compiled for a wider vector than the build's (chosen at run time by vector_width): AVX2,
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
int World::vector_width = World::cpu_vector_width();

int World::threads_for(int n) const {
  return std::max(1, std::min(threads, n / kMinDiscsPerThread));
}

// With threads, a step is two parallel regions (Verlet) or one (eqs. 18, 19): every fork and
// join costs microseconds, as much as a small world's pass. A drift also tells whether the lists
// must be rebuilt (a disc more than skin/2 from its list position); they are rebuilt right after
// it, or at the start of a step when stale (walls moved far, a wall removed, a restart).
void World::step() {
  const bool walls_move = !moving.empty();  // one test per step, none per contact
  bool far = false;
  if (scheme == Scheme::velocity_verlet) {
    far = kick_drift_eq18(0.5 * dt);  // v(t + dt/2); du = v(t + dt/2) dt; x += du
    if (walls_move) { kick_walls(0.5 * dt); drift_walls(false); }
  }
  if (walls_move && walls_moved_far()) neighbors.invalidate();
  if (far || neighbors.stale(discs)) {
    drop_pair_forces();  // the last step's totals, stale once this step runs: never beside a build's scratch
    rebuild_lists();
  }
  if (steps % kRebalanceEvery == 0) balance_blocks();  // and whenever they do not fit (compute_forces)
  // Eqs. (3)-(15) from the increments of the last move; then, for each thread's discs:
  switch (scheme) {
    case Scheme::paper_eq18: far = force_pass(Then::kick_drift_eq18, dt); break;  // (17), (18)
    case Scheme::paper_eq19: far = force_pass(Then::kick_drift_eq19, dt); break;  // (17), (19)
    case Scheme::velocity_verlet: far = force_pass(Then::kick, 0.5 * dt); break;  // v(t + dt)
  }
  if (walls_move) {
    if (scheme == Scheme::velocity_verlet) kick_walls(0.5 * dt);
    else { kick_walls(dt); drift_walls(scheme == Scheme::paper_eq19); }
  }
  if (far) rebuild_lists();  // eqs. (18), (19): for the next step's forces
  time += dt;
  ++steps;
  if (measure_increments && scheme == Scheme::velocity_verlet) increments_measured_step_ = steps;
  particle_steps += static_cast<double>(discs.size());
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
  select_kernel();
  geometry.link_points();
  const int slots = std::max(1, threads);
  touch_scratch_.assign(slots, std::vector<char>(geometry.obstacle_count() + 1, 0));
  dist_scratch_.assign(slots, std::vector<double>(geometry.obstacle_count() + 1, 0.0));
  deferred_.assign(slots, {});
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
  // Totals recorded over the old list (a build right after a recorded pass) name their pairs first.
  pair_totals.detach(neighbors.pairs);
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

void World::init() {
  prepare();
  force_pass(Then::nothing, 0.0);  // forces at the start (Verlet's first half kick uses them)
}

void World::drop_pair_forces() {
  pair_totals.clear();
  pair_forces_step = -1;
}

void World::size_pair_forces(std::size_t count) { pair_totals.start(count, neighbors.pairs.size()); }

bool World::force_pass(Then then, double h) {
  // Verlet's rest measure: the |v dt| of the move, before the closing kick overwrites v (the
  // force pass reads v, never writes it); parallel_sum's blocks, whatever the force blocks are.
  if (then == Then::kick && measure_increments) measure_increment_sums();
  const bool record = record_pair_forces;
  // Totals recorded by an earlier pass are stale after this one (pair_forces_current is false):
  // freed, so that they never sit beside a list build's scratch (one or the other at the peak).
  if (!record && pair_totals.allocated()) drop_pair_forces();
  const bool far = (this->*force_kernel_)(then, h);
  if (record) pair_forces_step = steps + (then == Then::nothing ? 0 : 1);  // a step's pass: the step it ends
  return far;
}

// Integration loops: each disc on its own, so any thread count gives the same bits. The kick
// and the drift of a disc go in one pass over the arrays (the same operations, in the same order,
// as a kick pass followed by a drift pass: one sweep of memory instead of two).
namespace {

// The loop of kick_drift_block, with every array a restrict parameter: GCC keeps restrict on
// parameters, not on local pointers; without it, it checked the arrays' overlap at run time,
// found more pairs to check than it will (10), and ran the loop one disc at a time. Now it runs
// two discs a vector (four with AVX2, below): the same operations on each disc, the same bits.
template <int D, bool ONE_KIND, bool PHI, bool FAR>  // D: 0 none, 1 eq. (18), 2 eq. (19)
inline __attribute__((always_inline)) long kick_drift_kernel(
    int n, double h, double step, const double* __restrict fx, const double* __restrict fy,
    const double* __restrict tq, const int* __restrict kd, const double* __restrict im, const double* __restrict ii,
    double* __restrict vx, double* __restrict vy, double* __restrict om, double* __restrict ux,
    double* __restrict uy, double* __restrict up, double* __restrict x, double* __restrict y,
    double* __restrict phi, const float* __restrict x0, const float* __restrict y0, double ox, double oy,
    double lim2) {
  const double im0 = ONE_KIND ? im[0] : 0, ii0 = ONE_KIND ? ii[0] : 0;  // one kind: its constants, loaded once
  long far = 0;
  for (int i = 0; i < n; ++i) {
    const double mi = ONE_KIND ? im0 : im[kd[i]], ji = ONE_KIND ? ii0 : ii[kd[i]];
    const double v = vx[i] + fx[i] * mi * h;  // (16), (17)
    const double w = vy[i] + fy[i] * mi * h;
    const double o = om[i] + tq[i] * ji * h;
    vx[i] = v; vy[i] = w; om[i] = o;
    if constexpr (D == 0) continue;
    double a, b, c;
    if constexpr (D == 2) {  // (19): the mean of the last increment and v dt
      a = 0.5 * (ux[i] + v * step);
      b = 0.5 * (uy[i] + w * step);
      c = 0.5 * (up[i] + o * step);
    } else {  // (18)
      a = v * step;
      b = w * step;
      c = o * step;
    }
    if constexpr (D == 2) { ux[i] = a; uy[i] = b; up[i] = c; }  // (18): v dt, read from v (increments())
    const double xn = x[i] + a, yn = y[i] + b;
    x[i] = xn;
    y[i] = yn;
    if constexpr (PHI) phi[i] += c;
    // The skin/2 test on the position just computed. A count, because an integer sum vectorises
    // and an |= of comparisons does not; a NaN position counts as not far, as it always did.
    if constexpr (FAR) {
      const double dx = (xn - ox) - x0[i], dy = (yn - oy) - y0[i];
      far += dx * dx + dy * dy > lim2 ? 1 : 0;
    }
  }
  return far;
}

// Compiled three times, as the pair law: for any x86-64 and, chosen at run time by
// World::vector_width, for AVX2 (four discs a vector; without AVX2 GCC does not vectorise the
// count of far discs, whose floats widen to doubles and whose count is 64-bit) and AVX-512 (eight).
#if defined(__x86_64__) && defined(__GNUC__)
template <int D, bool ONE_KIND, bool PHI, bool FAR, class... A>
DEM_TARGET_AVX2 long kick_drift_kernel_avx2(A... a) {
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR>(a...);
}
template <int D, bool ONE_KIND, bool PHI, bool FAR, class... A>
DEM_TARGET_AVX512 long kick_drift_kernel_avx512(A... a) {
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR>(a...);
}
#endif
template <int D, bool ONE_KIND, bool PHI, bool FAR, class... A>
long kick_drift_best(A... a) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (World::vector_width >= 8) return kick_drift_kernel_avx512<D, ONE_KIND, PHI, FAR>(a...);
  if (World::vector_width >= 4) return kick_drift_kernel_avx2<D, ONE_KIND, PHI, FAR>(a...);
#endif
  return kick_drift_kernel<D, ONE_KIND, PHI, FAR>(a...);
}

}  // namespace

template <World::Drift D, bool ONE_KIND, bool PHI>
bool World::kick_drift_block(double h, int i0, int i1) {
  Discs& d = discs;
  const auto at = [i0](auto& v) { return v.empty() ? nullptr : v.data() + i0; };  // eq. 19's and the angle's may be empty
  constexpr int k = D == Drift::none ? 0 : D == Drift::eq18 ? 1 : 2;
  // Stale lists (a restart, a wall removed): rebuilt before the next forces, nothing to test.
  const bool stale = D != Drift::none && neighbors.stale(discs);
  const auto run = [&](auto far) {
    return kick_drift_best<k, ONE_KIND, PHI, decltype(far)::value>(
        i1 - i0, h, dt, at(d.fx), at(d.fy), at(d.torque), at(d.kind), d.kinds.inv_mass.data(),
        d.kinds.inv_inertia.data(), at(d.vx), at(d.vy), at(d.omega), at(d.dux), at(d.duy), at(d.dphi), at(d.x),
        at(d.y), at(d.phi), far ? neighbors.reference_x().data() + i0 : nullptr,
        far ? neighbors.reference_y().data() + i0 : nullptr, neighbors.origin_x(), neighbors.origin_y(),
        neighbors.moved_far_limit2());
  };
  if (D == Drift::none || stale) {
    run(std::false_type{});
    return stale;
  }
  return run(std::true_type{}) != 0;
}

// kick_drift_block for this pass: one disc kind or several, the rotation angle kept or not.
template <World::Drift D>
bool World::kick_drift_for(double h, int i0, int i1) {
  const bool phi = !discs.phi.empty();
  if (one_kind()) {
    return phi ? kick_drift_block<D, true, true>(h, i0, i1) : kick_drift_block<D, true, false>(h, i0, i1);
  }
  return phi ? kick_drift_block<D, false, true>(h, i0, i1) : kick_drift_block<D, false, false>(h, i0, i1);
}

bool World::then_block(Then then, double h, int i0, int i1) {
  switch (then) {
    case Then::nothing: return false;
    case Then::kick:  // Verlet's closing half kick (its rest measure was taken before: force_pass)
      kick_drift_for<Drift::none>(h, i0, i1);
      return false;
    case Then::kick_drift_eq18: return kick_drift_for<Drift::eq18>(h, i0, i1);
    case Then::kick_drift_eq19: return kick_drift_for<Drift::eq19>(h, i0, i1);
  }
  return false;
}

// One parallel region: each thread an equal block of discs (block_start; the force pass balances
// its blocks by work, force_blocks: here every disc costs the same).
bool World::integrate(Then then, double h) {
  const int n = static_cast<int>(discs.size());
  const int nt = threads_for(n);
  if (nt <= 1) return then_block(then, h, 0, n);
  unsigned far = 0;
#pragma omp parallel num_threads(nt) reduction(| : far)
  {
    const int t = omp_thread_index();
    far |= then_block(then, h, block_start(n, nt, t), block_start(n, nt, t + 1)) ? 1u : 0u;
  }
  return far != 0;
}

bool World::kick_drift_eq18(double h) { return integrate(Then::kick_drift_eq18, h); }
bool World::kick_drift_eq19(double h) { return integrate(Then::kick_drift_eq19, h); }

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

template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH>
double World::pair_pass_for(std::size_t p0, std::size_t p1, int own_end, std::vector<Deferred>* later,
                            PairTotals::Force* record) {
  if (record)
    return one_kind() ? pair_pass<NS, NT, FC, LA, SHEAR, DASH, true, true>(p0, p1, own_end, later, record)
                     : pair_pass<NS, NT, FC, LA, SHEAR, DASH, true, false>(p0, p1, own_end, later, record);
  return one_kind() ? pair_pass<NS, NT, FC, LA, SHEAR, DASH, false, true>(p0, p1, own_end, later, nullptr)
                   : pair_pass<NS, NT, FC, LA, SHEAR, DASH, false, false>(p0, p1, own_end, later, nullptr);
}

// The law for n touching pairs of a block, in the block's arrays (pair_pass): no branch and no
// store that a later pair reads, so the compiler runs it two pairs at a time (SSE2) and the
// pairs' square roots and divisions overlap. The same operations, in the same order, as the
// law applied pair by pair: the same bits. One kind of disc: r_i + r_j is `sum1` (not gathered
// pair by pair).
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
static inline __attribute__((always_inline)) void pair_block_law(PairBlock& b, int n, const PairProps* __restrict props,
                                                                 double inv_dt, double sum1) {
  for (int k = 0; k < n; ++k) {
    const double R = std::sqrt(b.R2[k]);
    const double nx = b.dx[k] / R, ny = b.dy[k] / R;  // (4): cos(alpha), sin(alpha), from i to j
    const double ddx = b.ddx[k], ddy = b.ddy[k];
    const double du_n = ddx * nx + ddy * ny;                                          // (5a)
    const double overlap = (ONE_KIND ? sum1 : b.sum[k]) - R;
    double du_s = 0;
    if constexpr (SHEAR && LA == LeverArm::contact_point) {
      // (5b) with the arms r - overlap/2 (one kind: sum1 / 2 is r exactly)
      const double ai = (ONE_KIND ? 0.5 * sum1 : b.arm_i[k]) - 0.5 * overlap;
      const double aj = (ONE_KIND ? 0.5 * sum1 : b.arm_j[k]) - 0.5 * overlap;
      du_s = -ddx * ny + ddy * nx + ai * b.rot_i[k] + aj * b.rot_j[k];
      b.arm_i[k] = ai; b.arm_j[k] = aj;
    } else if constexpr (SHEAR) {
      du_s = -ddx * ny + ddy * nx + b.rot_i[k] + b.rot_j[k];  // (5b)
    }
    double fn, fs;
    contact_law<NS, NT, FC, SHEAR, DASH>(props[ONE_KIND ? 0 : b.prop[k]], overlap, du_n, du_s, inv_dt, b.en[k],
                                         b.es[k], fn, fs);
    double fx = -fn * nx, fy = -fn * ny;  // (15a), (15b) terms on i
    if constexpr (SHEAR) {
      fx += fs * ny;
      fy -= fs * nx;
    }
    b.overlap[k] = overlap;  // (a max taken here instead would keep GCC, without -ffast-math, from vectorising the loop)
    b.fn[k] = fn; b.fs[k] = fs;
    b.fx[k] = fx; b.fy[k] = fy;
  }
}

// The block's law compiled three times: for any x86-64 (two pairs a vector) and, chosen at run
// time by World::vector_width, for AVX2 (four) and AVX-512 (eight). IEEE operations give the
// same bits at any width, and no contraction into FMA (-ffp-contract=off, and the AVX2 version
// does not enable FMA).
#if defined(__x86_64__) && defined(__GNUC__)
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
DEM_TARGET_AVX2 static void pair_block_law_avx2(PairBlock& b, int n, const PairProps* __restrict props, double inv_dt,
                                                double sum1) {
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1);
}
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
DEM_TARGET_AVX512 static void pair_block_law_avx512(PairBlock& b, int n, const PairProps* __restrict props,
                                                    double inv_dt, double sum1) {
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1);
}
#endif
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool ONE_KIND>
static void pair_block_law_best(PairBlock& b, int n, const PairProps* __restrict props, double inv_dt, double sum1) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (World::vector_width >= 8) return pair_block_law_avx512<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1);
  if (World::vector_width >= 4) return pair_block_law_avx2<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1);
#endif
  pair_block_law<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, props, inv_dt, sum1);
}

// Disc-disc contacts [p0, p1) of the sorted pair list, a block of touching pairs at a time: the
// geometry of each pair is gathered (a pair found apart loses its history there), the law runs
// on the block's arrays (pair_block_law), and the results are added to the discs in list order.
// The i side of each pair is added at once; the j side too when j < own_end, otherwise (j belongs
// to another thread's discs) it is kept in `later` and added after the parallel part, in a fixed
// order. RECORD: the totals of the touching pairs are written from `record` on, room for
// touching_pairs(p0, p1) of them, and each touching pair's bit set in pair_totals' bits over the
// list. Returns the largest overlap.
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool SHEAR, bool DASH, bool RECORD, bool ONE_KIND>
double World::pair_pass(std::size_t p0, std::size_t p1, int own_end, std::vector<Deferred>* later,
                        PairTotals::Force* record) {
  Discs& d = discs;
  const double inv_dt = 1.0 / dt;
  PairContact* __restrict pc = neighbors.pairs.data();
  const Increments u = increments();
  // Distinct arrays: restrict lets the compiler keep values in registers across the stores.
  const double* __restrict x = d.x.data(); const double* __restrict y = d.y.data();
  // Radius and material by kind: a small table, read through each disc's kind.
  const int* __restrict kd = d.kind.data();
  const double* __restrict kr = d.kinds.r.data(); const int* __restrict kmat = d.kinds.material.data();
  const double* __restrict ux = u.x; const double* __restrict uy = u.y; const double* __restrict uphi = u.phi;
  const double uf = u.factor;
  double* __restrict fxa = d.fx.data(); double* __restrict fya = d.fy.data(); double* __restrict tq = d.torque.data();
  const int n_mat = n_materials;
  // One kind of disc: one pair of materials, its constants fetched once.
  const PairProps* law_props = ONE_KIND ? &props[kmat[0] * n_mat + kmat[0]] : props.data();
  const double sum1 = ONE_KIND ? kr[0] + kr[0] : 0.0;  // r_i + r_j of every pair, one kind of disc
  PairBlock b;  // on this thread's stack (20 kB), hot in its cache
  double worst = 0;
  // RECORD: the touching pairs' bits, gathered a word at a time and or-ed into the list's bits
  // (a thread's first and last words may be shared with its neighbours': atomic, in any order).
  std::uint64_t* const bits = RECORD ? pair_totals.bits() : nullptr;
  std::size_t word = 0;
  std::uint64_t word_bits = 0;
  const auto flush_bits = [&] {
    if (word_bits != 0) __atomic_fetch_or(&bits[word], word_bits, __ATOMIC_RELAXED);
  };
  for (std::size_t p = p0; p < p1;) {
    int n = 0;
    for (; p < p1 && n < PairBlock::kSize; ++p) {
      PairContact& c = pc[p];
      const int i = c.i, j = c.j;
      const int ki = ONE_KIND ? 0 : kd[i], kj = ONE_KIND ? 0 : kd[j];
      const double ri = kr[ki], rj = kr[kj];
      const double dx = x[j] - x[i], dy = y[j] - y[i];
      const double R2 = dx * dx + dy * dy, sum = ri + rj;
      if (apart(R2, sum)) {  // (3): apart; the contact and its history end
        c.en = c.es = 0;
        continue;
      }
      b.pair[n] = static_cast<int>(p - p0);
      b.dx[n] = dx; b.dy[n] = dy; b.R2[n] = R2;
      if constexpr (!ONE_KIND) b.sum[n] = sum;
      b.ddx[n] = ux[i] * uf - ux[j] * uf;  // the relative increment of (5)
      b.ddy[n] = uy[i] * uf - uy[j] * uf;
      if constexpr (SHEAR && LA == LeverArm::contact_point) {  // the arms need the overlap: pair_block_law
        b.rot_i[n] = uphi[i] * uf;
        b.rot_j[n] = uphi[j] * uf;
        if constexpr (!ONE_KIND) { b.arm_i[n] = ri; b.arm_j[n] = rj; }
      } else if constexpr (SHEAR) {
        b.rot_i[n] = ri * (uphi[i] * uf);
        b.rot_j[n] = rj * (uphi[j] * uf);
      }
      if constexpr (!ONE_KIND) b.prop[n] = kmat[ki] * n_mat + kmat[kj];
      b.en[n] = c.en; b.es[n] = c.es;
      ++n;
    }
    pair_block_law_best<NS, NT, FC, LA, SHEAR, DASH, ONE_KIND>(b, n, law_props, inv_dt, sum1);
    // Disc i's sums in registers while its pairs follow one another (the list is sorted by i; a j
    // is never the current i): the same additions in the same order, without a store and a
    // reload of fx[i], fy[i], torque[i] between two pairs of one disc.
    int cur = -1;
    double ax = 0, ay = 0, at = 0;
    const auto put_back = [&] {  // the current disc's sums to its arrays
      if (cur < 0) return;
      fxa[cur] = ax; fya[cur] = ay;
      if constexpr (SHEAR) tq[cur] = at;
    };
    for (int k = 0; k < n; ++k) {
      PairContact& c = pc[p0 + static_cast<std::size_t>(b.pair[k])];
      const int i = c.i, j = c.j;
      c.en = b.en[k]; c.es = b.es[k];
      worst = std::max(worst, b.overlap[k]);
      const double fx = b.fx[k], fy = b.fy[k], fs = b.fs[k];
      if constexpr (RECORD) {
        *record++ = PairTotals::Force{b.fn[k], fs};
        const std::size_t q = p0 + static_cast<std::size_t>(b.pair[k]);
        if ((q >> 6) != word) {
          flush_bits();
          word = q >> 6;
          word_bits = 0;
        }
        word_bits |= std::uint64_t{1} << (q & 63);
      }
      if (i != cur) {
        put_back();
        cur = i;
        ax = fxa[i]; ay = fya[i];
        if constexpr (SHEAR) at = tq[i];
      }
      ax += fx; ay += fy;
      constexpr bool CP = LA == LeverArm::contact_point;
      if constexpr (SHEAR) at -= (CP ? b.arm_i[k] : kr[ONE_KIND ? 0 : kd[i]]) * fs;  // (15c); f_s is the same seen from j (5b is symmetric)
      const double rj = CP ? b.arm_j[k] : kr[ONE_KIND ? 0 : kd[j]];
      if (j < own_end) {
        fxa[j] -= fx; fya[j] -= fy;
        if constexpr (SHEAR) tq[j] -= rj * fs;
      } else {
        later->push_back(Deferred{j, fx, fy, SHEAR ? rj * fs : 0.0});
      }
    }
    put_back();
  }
  if constexpr (RECORD) flush_bits();
  return worst;
}

// Disc-obstacle contacts [w0, w1) of the wall list (whole groups of one disc), with the
// per-thread scratch `slot`. Returns the largest overlap.
template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool MOVING, bool SHEAR, bool DASH>
double World::wall_forces(std::size_t w0, std::size_t w1, int slot) {
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
        c.nx = (h.px - d.x[i]) / h.dist;
        c.ny = (h.py - d.y[i]) / h.dist;
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
      const double nx = c.nx, ny = c.ny;
      const double overlap = d.r(i) - dist;
      // The lever arm of (5b), (15c): r, or r - overlap/2 (the middle of the overlap). A moving
      // wall's own point stays the closest point (px, py) of its surface.
      const double arm = LA == LeverArm::contact_point ? d.r(i) - 0.5 * overlap : d.r(i);
      double du_n, du_s;
      if constexpr (MOVING) {
        // The wall's material point at the contact moved too: (5) with j the wall.
        const ObstacleMotion& m = moving.motion[c.k];
        const double ddx = u.x[i] * u.factor - (m.dux - m.dtheta * (c.py - m.pivot_y));
        const double ddy = u.y[i] * u.factor - (m.duy + m.dtheta * (c.px - m.pivot_x));
        du_n = ddx * nx + ddy * ny;                                      // (5a)
        du_s = -ddx * ny + ddy * nx + arm * (u.phi[i] * u.factor);       // (5b)
      } else {
        const double uxi = u.x[i] * u.factor, uyi = u.y[i] * u.factor;
        du_n = uxi * nx + uyi * ny;                                      // (5a)
        du_s = -uxi * ny + uyi * nx + arm * (u.phi[i] * u.factor);       // (5b)
      }
      worst = std::max(worst, overlap);
      const int km = c.k < n_walls ? geometry.walls[c.k].material
                                   : geometry.points[c.k - n_walls].material;
      contact_law<NS, NT, FC, SHEAR, DASH>(props[d.material(i) * n_mat + km], overlap, du_n, du_s, inv_dt,
                                           c.en, c.es, c.fn, c.fs);
      d.fx[i] += -c.fn * nx + c.fs * ny;  // (15a)
      d.fy[i] += -c.fn * ny - c.fs * nx;  // (15b)
      d.torque[i] -= arm * c.fs;          // (15c)
      if constexpr (MOVING) {  // the reaction on the obstacle
        ObstacleMotion& m = moving.motion[c.k];
        const double wx = c.fn * nx - c.fs * ny, wy = c.fn * ny + c.fs * nx;
        m.fx += wx;
        m.fy += wy;
        m.moment += (c.px - m.pivot_x) * wy - (c.py - m.pivot_y) * wx;
      }
    }
    b = e;
  }
  return worst;
}

template <NormalSpring NS, NoTension NT, FrictionCap FC, LeverArm LA, bool BONDS, bool MOVING, bool SHEAR, bool DASH>
bool World::compute_forces(Then then, double h) {
  Discs& d = discs;
  const int n = static_cast<int>(d.size());
  const double inv_dt = 1.0 / dt;
  const int nt = (BONDS || MOVING) ? 1 : threads_for(n);
  double worst = 0;
  const bool record = record_pair_forces;
  if (nt == 1) {
    start_resultants(0, n);
    const std::size_t np = neighbors.pairs.size();
    if (record) size_pair_forces(touching_pairs(0, np));
    worst = pair_pass_for<NS, NT, FC, LA, SHEAR, DASH>(0, np, n, nullptr, record ? pair_totals.forces() : nullptr);
  } else {
    // Threads own contiguous blocks of discs (force_blocks: of equal work, set every
    // kRebalanceEvery steps); a pair is computed by the owner of its i. What a thread adds to a later block's
    // discs is added by that block's owner once all are done, in thread order: a given thread
    // count always sums in the same order (bit-identical runs). Then each thread integrates its
    // own discs.
    if (!blocks_fit()) balance_blocks();  // other threads or discs than at the last balance
    std::vector<double>& part = thread_overlap_;
    part.assign(nt, 0.0);
    unsigned far = 0;
    const auto& pairs = neighbors.pairs;
    const auto& wl = neighbors.walls;
#pragma omp parallel num_threads(nt) reduction(| : far)
    {
      const int t = omp_thread_index();
      const int i0 = force_blocks[t], i1 = force_blocks[t + 1];
      const auto by_i = [](const auto& c, int i) { return c.i < i; };
      const std::size_t p0 = std::lower_bound(pairs.begin(), pairs.end(), i0, by_i) - pairs.begin();
      const std::size_t p1 = std::lower_bound(pairs.begin(), pairs.end(), i1, by_i) - pairs.begin();
      const std::size_t w0 = std::lower_bound(wl.begin(), wl.end(), i0, by_i) - wl.begin();
      const std::size_t w1 = std::lower_bound(wl.begin(), wl.end(), i1, by_i) - wl.begin();
      deferred_[t].value.clear();
      start_resultants(i0, i1);
      // A recorded pass: each thread writes its touching pairs' totals into its own slice of
      // pair_totals, sized once to the exact count (the list's order; no growth, no copy).
      PairTotals::Force* mine = nullptr;
      if (record) {  // the same branch on every thread
        touching_[t].value = touching_pairs(p0, p1);
#pragma omp barrier
        if (t == 0) {  // the main thread: its malloc arena, where the list is freed again
          std::size_t total = 0;
          for (int u = 0; u < nt; ++u) total += touching_[u].value;
          size_pair_forces(total);
        }
#pragma omp barrier
        std::size_t offset = 0;
        for (int u = 0; u < t; ++u) offset += touching_[u].value;
        mine = pair_totals.forces() + offset;
      }
      // Walls before pairs: the order (and the bits) that gcc gave the former
      // std::max(pairs(), walls()), whose arguments it evaluates right to left; now explicit.
      const double ww = wall_forces<NS, NT, FC, LA, false, SHEAR, DASH>(w0, w1, t);
      const double pw = pair_pass_for<NS, NT, FC, LA, SHEAR, DASH>(p0, p1, i1, &deferred_[t].value, mine);
      part[t] = std::max(pw, ww);
#pragma omp barrier
      for (int u = 0; u < t; ++u)  // earlier threads' reactions on this block, in their order
        for (const Deferred& q : deferred_[u].value) {
          if (q.j < i0 || q.j >= i1) continue;
          d.fx[q.j] -= q.fx; d.fy[q.j] -= q.fy;
          d.torque[q.j] -= q.tq;
        }
      far |= then_block(then, h, i0, i1) ? 1u : 0u;
    }
    for (int t = 0; t < nt; ++t) worst = std::max(worst, part[t]);
    max_overlap = worst;
    return far != 0;
  }

  if constexpr (BONDS) {
    // Paper 2: inside a cluster both springs act in tension and without limit, with dashpots.
    const Increments u = increments();
    for (Bond& b : bonds) {
      const int i = b.i, j = b.j;
      const double dx = d.x[j] - d.x[i], dy = d.y[j] - d.y[i];
      const double R = std::sqrt(dx * dx + dy * dy);
      const double nx = dx / R, ny = dy / R;
      const double ddx = u.x[i] * u.factor - u.x[j] * u.factor, ddy = u.y[i] * u.factor - u.y[j] * u.factor;
      const double du_n = ddx * nx + ddy * ny;                                       // (5a)
      const double du_s = -ddx * ny + ddy * nx + b.ai * (u.phi[i] * u.factor) + b.aj * (u.phi[j] * u.factor);  // (5b)
      const PairProps& p = pair(d.material(i), d.material(j));
      if constexpr (NS == NormalSpring::incremental)
        b.en += p.kn * du_n;        // (7a), without (8): tension allowed
      else
        b.en = p.kn * (b.rest - R);  // the overlap option: measured from the bonded distance
      b.es += p.ks * du_s;          // (11a), without (13): no cap
      b.fn = b.en + p.eta_n * du_n * inv_dt;
      b.fs = b.es + p.eta_s * du_s * inv_dt;
      worst = std::max(worst, d.r(i) + d.r(j) - R);
      const double fx = -b.fn * nx + b.fs * ny;
      const double fy = -b.fn * ny - b.fs * nx;
      d.fx[i] += fx; d.fy[i] += fy;
      d.fx[j] -= fx; d.fy[j] -= fy;
      d.torque[i] -= b.ai * b.fs;
      d.torque[j] -= b.aj * b.fs;
    }
  }
  if constexpr (MOVING)
    for (ObstacleMotion& m : moving.motion) m.fx = m.fy = m.moment = 0;
  worst = std::max(worst, wall_forces<NS, NT, FC, LA, MOVING, SHEAR, DASH>(0, neighbors.walls.size(), 0));
  max_overlap = worst;
  return then_block(then, h, 0, n);
}

void World::select_kernel() {
  // Every option combination is its own compiled kernel (no branch per contact). Bonds and
  // moving walls are compile-time flags too, and so are a scene without shear (every pair
  // shear-free) and without dashpots: a scene pays only for what it uses. Bonds and moving walls
  // come with the full law (shear and dashpots), which their scenes use.
  const bool has_bonds = !bonds.empty(), has_moving = !moving.empty();
  bool shear = false, dash = false;
  for (const PairProps& p : props) {
    const bool shear_free = (p.ks == 0 && p.eta_s == 0) || (p.mu == 0 && p.ks > 0);  // cap 0 holds e_s = 0
    shear = shear || !shear_free;
    dash = dash || p.eta_n != 0 || p.eta_s != 0;
  }
  if (has_bonds || has_moving) shear = dash = true;
  kernel_shear = shear;
  kernel_dashpots = dash;
  // The lever arm matters only where there is shear: a shear-free scene runs the radius kernel
  // (the same result). The contact-point arm comes with the kernels that have shear.
  const LeverArm lever = shear ? options.lever_arm : LeverArm::radius;
#define DEM_KB(NS, NT, FC, LA, B, M, S, D)                                                                 \
  if (lever == LeverArm::LA && has_bonds == B && has_moving == M && shear == S && dash == D) {              \
    force_kernel_ = &World::compute_forces<NormalSpring::NS, NoTension::NT, FrictionCap::FC, LeverArm::LA, B, M, S, D>; \
    return;                                                                                                \
  }
#define DEM_K(NS, NT, FC)                                                                                          \
  if (options.normal_spring == NormalSpring::NS && options.no_tension == NoTension::NT &&                             \
      options.friction_cap == FrictionCap::FC) {                                                                    \
    DEM_KB(NS, NT, FC, radius, false, false, true, true) DEM_KB(NS, NT, FC, radius, true, false, true, true)        \
    DEM_KB(NS, NT, FC, radius, false, true, true, true) DEM_KB(NS, NT, FC, radius, true, true, true, true)          \
    DEM_KB(NS, NT, FC, radius, false, false, false, true) DEM_KB(NS, NT, FC, radius, false, false, true, false)     \
    DEM_KB(NS, NT, FC, radius, false, false, false, false)                                                          \
    DEM_KB(NS, NT, FC, contact_point, false, false, true, true) DEM_KB(NS, NT, FC, contact_point, true, false, true, true) \
    DEM_KB(NS, NT, FC, contact_point, false, true, true, true) DEM_KB(NS, NT, FC, contact_point, true, true, true, true)   \
    DEM_KB(NS, NT, FC, contact_point, false, false, true, false)                                                    \
  }
#define DEM_K2(NS, NT) DEM_K(NS, NT, elastic) DEM_K(NS, NT, total)
#define DEM_K3(NS) DEM_K2(NS, elastic) DEM_K2(NS, total) DEM_K2(NS, overlap)
  DEM_K3(incremental)
  DEM_K3(overlap)
#undef DEM_K3
#undef DEM_K2
#undef DEM_K
#undef DEM_KB
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
  neighbors.compact(removed);
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

// The sums of parallel_sum (its blocks, each summed in order): the same bits as summing stored
// increments with it, whichever threads run this step's passes. One block a thread.
void World::measure_increment_sums() {
  const int n = static_cast<int>(discs.size());
  const int nb = threads_for(n);
  const double* vx = discs.vx.data(); const double* vy = discs.vy.data();
#pragma omp parallel for schedule(static) num_threads(nb)
  for (int b = 0; b < nb; ++b) {
    double sx = 0, sy = 0;
    for (int i = block_start(n, nb, b); i < block_start(n, nb, b + 1); ++i) {
      sx += std::abs(vx[i] * dt);
      sy += std::abs(vy[i] * dt);
    }
    increment_sums_[b].value = {sx, sy};
  }
}

void World::mean_abs_increment(double& mx, double& my) const {
  const long n = static_cast<long>(discs.size());
  const int nt = threads_for(static_cast<int>(n));
  if (scheme == Scheme::velocity_verlet) {
    if (increments_measured_step_ != steps)
      throw std::logic_error("mean_abs_increment: this Verlet step did not measure its increments");
    mx = my = 0;
    for (int b = 0; b < (n ? nt : 0); ++b) { mx += increment_sums_[b].value[0]; my += increment_sums_[b].value[1]; }
  } else {
    const Increments u = increments();
    mx = parallel_sum(n, nt, [&](long i) { return std::abs(u.x[i] * u.factor); });
    my = parallel_sum(n, nt, [&](long i) { return std::abs(u.y[i] * u.factor); });
  }
  if (n) { mx /= static_cast<double>(n); my /= static_cast<double>(n); }
}

double World::kinetic_energy() const {
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return parallel_sum(n, threads_for(static_cast<int>(n)), [&](long i) {
    return 0.5 * d.mass(i) * (d.vx[i] * d.vx[i] + d.vy[i] * d.vy[i]) +
           0.5 / d.inv_inertia(i) * d.omega[i] * d.omega[i];
  });
}

bool World::all_finite() const {
  const Discs& d = discs;
  const long n = static_cast<long>(d.size());
  return !parallel_any(n, threads_for(static_cast<int>(n)), [&](long i) {
    return !std::isfinite(d.x[i]) || !std::isfinite(d.y[i]) || !std::isfinite(d.vx[i]) ||
           !std::isfinite(d.vy[i]) || !std::isfinite(d.omega[i]);
  });
}

const char* to_string(NormalSpring v) { return v == NormalSpring::incremental ? "incremental" : "overlap"; }
const char* to_string(NoTension v) {
  return v == NoTension::elastic ? "elastic" : v == NoTension::total ? "total" : "overlap";
}
const char* to_string(FrictionCap v) { return v == FrictionCap::elastic ? "elastic" : "total"; }
const char* to_string(LeverArm v) { return v == LeverArm::radius ? "radius" : "contact_point"; }
const char* to_string(Scheme v) {
  return v == Scheme::paper_eq18 ? "paper_eq18" : v == Scheme::paper_eq19 ? "paper_eq19" : "velocity_verlet";
}

}  // namespace dem
