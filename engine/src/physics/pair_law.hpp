// The contact law on a block of disc pairs (PairBlock), eqs. (4), (5), (6)-(14), (15a, b), at
// each vector width: what a pair stage (contact_stages.hpp) runs between its gather and its add.
// Included by the kernel list (kernel_list.cpp) alone, which compiles it for each of its rows.
#pragma once

#include <cmath>

#include "physics/contact_frame.hpp"
#include "physics/contact_law.hpp"
#include "physics/vector_target.hpp"
#include "physics/world.hpp"

namespace dem {

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
// for AVX-512 (eight); the kernel list holds all three, a world runs its width's. IEEE
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
// The block law at W doubles a vector (a row of the kernel list holds each width's). A
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

}  // namespace dem
