// Contact constants from elasticity: the paper's section 3, eqs. (20)-(26).
#pragma once

namespace dem {

// Inputs of eqs. (22)-(23); cgs by default (the paper's Table 1 column headings).
struct ElasticInputs {
  double E;             // Young's modulus [dyn/cm^2]
  double nu = 0.3;      // Poisson's ratio [-]
  double r = 1.0;       // disc radius (both discs equal) [cm]
  double rho = 2.65;    // density [g/cm^3]
  double q = 30.0 * 980.665;  // line load of eq. (22) [dyn/cm]; never printed in the paper,
                              // ~30 gf/cm reproduces Table 1 (see docs/model.md)
  double g = 980.0;     // gravity used to print X/(rho g) [cm/s^2]
  double s = 0.25;      // K_s / K_n, eq. (24)
};

struct ElasticParams {
  double b;        // contact width, eq. (22b) [cm]
  double delta;    // approach of centres under q, eq. (22a) [cm]
  double kn;       // K_n = q / delta, eq. (23) [dyn/cm per cm]
  double ks;       // K_s = s K_n, eq. (24)
  double mass;     // rho pi r^2 per unit thickness [g/cm]
  double eta_n;    // 2 sqrt(m K_n), eqs. (20), (25a) [g/s per cm]
  double eta_s;    // eta_n sqrt(s), eq. (25b)
  double dt_eq26;  // eta_n / K_n, eq. (26) [s]
  double dt_eq21;  // Cundall's 2 sqrt(m / K_n), eq. (21) [s]
};

// Eqs. (22)-(26) with the 2/3 of eq. (22a) (the scan's 1.5 in eq. (23) is a misprint).
ElasticParams elastic_params(const ElasticInputs& in);

constexpr double kKgfPerCm2 = 980665.0;  // 1 kgf/cm^2 in dyn/cm^2

}  // namespace dem
