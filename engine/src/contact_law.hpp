// The paper's contact law for one contact over one step, eqs. (6)-(14). The options are
// template parameters so the per-contact loop carries no branch for a variant a scene does not
// use (docs/scene.md lists them).
#pragma once

#include <algorithm>
#include <cmath>

#include "model.hpp"

namespace dem {

// du_n: approach increment (5a); du_s: shear increment (5b); overlap = r_i + r_j - R >= 0.
// en, es: elastic forces carried from the last step (updated). fn, fs: total forces (out).
// SHEAR = false: every pair of the scene is shear-free (no shear spring and dashpot, or mu = 0
// with a shear spring, so the cap holds e_s at 0): the shear part is not computed (same result).
// DASH = false: no pair has a dashpot: the dashpot terms are not computed (same result).
template <NormalSpring NS, NoTension NT, FrictionCap FC, bool SHEAR = true, bool DASH = true>
inline void contact_law(const PairProps& p, double overlap, double du_n, double du_s,
                        double inv_dt, double& en, double& es, double& fn, double& fs) {
  // Normal: spring and dashpot in parallel.
  if constexpr (NS == NormalSpring::incremental)
    en += p.kn * du_n;  // (6a), (7a)
  else
    en = p.kn * overlap;
  double dn = 0;
  if constexpr (DASH) dn = p.eta_n * du_n * inv_dt;  // (6b), (7b): the dashpot is not accumulated

  if constexpr (NT == NoTension::elastic) {
    if (en < 0) {  // (8), (12): no tension in the elastic part; the contact carries nothing
      en = es = fn = fs = 0;
      return;
    }
    fn = en + dn;  // (9) -- may be tensile through the dashpot alone, as written
  } else if constexpr (NT == NoTension::total) {
    en = std::max(en, 0.0);
    fn = std::max(en + dn, 0.0);
  } else {
    fn = en + dn;  // viscous pull allowed while the discs overlap
  }

  if constexpr (!SHEAR) {
    fs = 0;
    return;
  }
  // Shear: spring and dashpot in parallel, the spring capped by Coulomb friction.
  es += p.ks * du_s;                          // (10a), (11a)
  double ds = 0;
  if constexpr (DASH) ds = p.eta_s * du_s * inv_dt;  // (10b), (11b)
  const double cap = p.mu * (FC == FrictionCap::elastic ? std::max(en, 0.0) : std::abs(fn));
  if (std::abs(es) > cap) {                   // (13a): capped, not reset
    es = std::copysign(cap, es);
    ds = 0;                                   // (13b): no shear dashpot while sliding
  }
  fs = es + ds;                               // (14)
}

}  // namespace dem
