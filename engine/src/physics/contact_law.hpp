// The paper's contact law for one contact over one step, eqs. (6)-(14). The options are
// template parameters so the per-contact loop carries no branch for a variant a scene does not
// use (docs/scene.md lists them). Paper 2's cluster bonds are the variant without the two
// conditions: NoTension::none and FrictionCap::none (bond_law).
#pragma once

#include <algorithm>
#include <cmath>

#include "physics/model.hpp"

namespace dem {

// du_n: approach increment (5a); du_s: shear increment (5b); overlap = r_i + r_j - R >= 0.
// en, es: elastic forces carried from the last step (updated). fn, fs: total forces (out).
// SHEAR = false: every pair of the scene is shear-free (no shear spring and dashpot, or mu = 0
// with a shear spring, so the cap holds e_s at 0): the shear part is not computed (same result).
// DASH = false: no pair has a dashpot: the dashpot terms are not computed (same result).
// dash_n, dash_s: the increments whose rate (times inv_dt) the dashpots see; contact_law passes
// du_n, du_s (the paper's), velocity_verlet_onset the predicted v(t + dt) dt (onset.cpp).
template <NormalSpring NS, NoTension NT, FrictionCap FC, bool SHEAR = true, bool DASH = true>
inline void contact_law_dash(const PairProps& p, double overlap, double du_n, double du_s, double dash_n,
                             double dash_s, double inv_dt, double& en, double& es, double& fn, double& fs) {
  // Choices are selects, not branches: in a dense packing whether a contact slides or goes slack
  // is data the branch predictor cannot learn, and a select gives the very same values.
  // Normal: spring and dashpot in parallel.
  if constexpr (NS == NormalSpring::incremental)
    en += p.kn * du_n;  // (6a), (7a)
  else
    en = p.kn * overlap;
  double dn = 0;
  if constexpr (DASH) dn = p.eta_n * dash_n * inv_dt;  // (6b), (7b): the dashpot is not accumulated

  bool slack = false;  // NoTension::elastic, (8), (12): the elastic part in tension; the contact carries nothing
  if constexpr (NT == NoTension::elastic) {
    slack = en < 0;
    fn = en + dn;  // (9) -- may be tensile through the dashpot alone, as written
  } else if constexpr (NT == NoTension::total) {
    en = std::max(en, 0.0);
    fn = std::max(en + dn, 0.0);
  } else {
    fn = en + dn;  // overlap: viscous pull allowed while the discs overlap; none: tension too
  }

  double s = 0;  // the new e_s
  if constexpr (SHEAR) {
    // Shear: spring and dashpot in parallel, the spring capped by Coulomb friction.
    s = es + p.ks * du_s;                       // (10a), (11a)
    double ds = 0;
    if constexpr (DASH) ds = p.eta_s * dash_s * inv_dt;  // (10b), (11b)
    if constexpr (FC != FrictionCap::none) {
      const double cap = p.mu * (FC == FrictionCap::elastic ? std::max(en, 0.0) : std::abs(fn));
      const bool slide = std::abs(s) > cap;     // (13a): capped, not reset
      s = slide ? std::copysign(cap, s) : s;
      ds = slide ? 0.0 : ds;                    // (13b): no shear dashpot while sliding
    }
    fs = s + ds;                                // (14)
  } else {
    fs = 0;
  }
  if constexpr (NT == NoTension::elastic) {
    en = slack ? 0.0 : en;
    fn = slack ? 0.0 : fn;
    s = slack ? 0.0 : s;
    fs = slack ? 0.0 : fs;
  }
  if constexpr (SHEAR) es = s;
  else if constexpr (NT == NoTension::elastic) es = slack ? 0.0 : es;
}

// The law with the dashpots on the same increments as the springs: every scheme but
// velocity_verlet_onset (the very operations of the paper's law).
template <NormalSpring NS, NoTension NT, FrictionCap FC, bool SHEAR = true, bool DASH = true>
inline void contact_law(const PairProps& p, double overlap, double du_n, double du_s, double inv_dt,
                        double& en, double& es, double& fn, double& fs) {
  contact_law_dash<NS, NT, FC, SHEAR, DASH>(p, overlap, du_n, du_s, du_n, du_s, inv_dt, en, es, fn, fs);
}

// Paper 2: inside a cluster both springs act in tension and without limit, with their dashpots.
// overlap: for NormalSpring::overlap, the shortening from the bonded distance.
template <NormalSpring NS>
inline void bond_law(const PairProps& p, double overlap, double du_n, double du_s, double inv_dt, double& en,
                     double& es, double& fn, double& fs) {
  contact_law<NS, NoTension::none, FrictionCap::none>(p, overlap, du_n, du_s, inv_dt, en, es, fn, fs);
}

}  // namespace dem
