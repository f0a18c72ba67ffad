// The contact stages of a force pass, one block of discs at a time: disc pairs (a block of pairs
// gathered, the law of pair_law.hpp, the forces added), discs on walls and points, paper 2's
// bonds. Templates of the law and the features a scene uses; included by the kernel list
// (kernel_list.cpp) alone, which compiles the rows it declares.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "physics/contact_frame.hpp"
#include "physics/contact_law.hpp"
#include "physics/world.hpp"

namespace dem {

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
template <LeverArm LA, bool SHEAR, bool RECORD, bool ONE_KIND, bool CROSS>
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
// (5), and the reactions on them are summed for the plates' move. The law is the row's
// (Kernel::contact_law): a call a touching wall contact, a few in a silo against its pairs.
template <LeverArm LA, bool MOVING, bool SHEAR>
void World::wall_contacts(ForceBlock& blk) {
  const ContactLaw law = kernel_->contact_law;
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
      law(props[d.material(i) * n_mat + km], overlap, du_n, du_s, inv_dt, c.en, c.es, c.fn, c.fs);  // (6)-(14)
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

}  // namespace dem
