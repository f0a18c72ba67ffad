// The move of the discs, eqs. (16)-(19): the kick and the drift in one sweep, compiled for each
// way a step asks for it and at each vector width (kernels.hpp).
#include <array>
#include <utility>

#include "physics/integrator.hpp"
#include "physics/parallel.hpp"
#include "physics/vector_target.hpp"
#include "physics/world.hpp"

namespace dem {

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

// The move rows of the kernel list (kernels.hpp: kMoves), compiled at each vector width.
using MoveKernel = long (*)(const MoveArrays&);
template <int W, std::size_t M>
constexpr MoveKernel move_kernel() {
  constexpr MoveKey key = kMoves[M];
  constexpr int D = key.drift == Drift::none ? 0 : key.drift == Drift::eq18 ? 1 : 2;
  constexpr bool ONE_KIND = key.one_kind, PHI = key.angle, FAR = key.far_test, RESET = key.reset, OWED = key.owed;
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
// [width index][row of kMoves]
constexpr std::array<MoveKernel, kMoveCount> kMoveKernels[3] = {move_kernels<2>(std::make_index_sequence<kMoveCount>{}),
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
  const MoveKey key{D == 0 ? Drift::none : D == 1 ? Drift::eq18 : Drift::eq19, reset, owed, one_kind(),
                    D != 0 && !d.phi.empty(), test};
  const long far = kMoveKernels[width_index()][row_of(kMoves, key)](a);
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

}  // namespace dem
