// Table 1 of the paper, all 15 printed entries, from eqs. (22)-(26) (docs/model.md gives the
// corrected eta exponents).
#include <gtest/gtest.h>

#include <cmath>

#include "physics/elastic_params.hpp"

using namespace dem;

TEST(ElasticParams, ReproducesTable1Within1Percent) {
  const double E[5] = {7.5e2, 1e3, 1e4, 1e5, 1e6};  // kgf/cm^2
  const double kn[5] = {3.64e4, 4.75e4, 4.06e5, 3.55e6, 3.16e7};   // K_n/(rho g) [cm]
  const double eta[5] = {21.6, 24.7, 72.2, 213, 636};              // eta_n/(rho g) [cm s]
  const double dt[5] = {5.94e-4, 5.20e-4, 1.78e-4, 6.01e-5, 2.02e-5};  // eq. (26) [s]
  for (int k = 0; k < 5; ++k) {
    ElasticInputs in;
    in.E = E[k] * kKgfPerCm2;
    const ElasticParams p = elastic_params(in);
    const double rg = in.rho * in.g;
    EXPECT_NEAR(p.kn / rg, kn[k], 0.01 * kn[k]) << "E = " << E[k];
    EXPECT_NEAR(p.eta_n / rg, eta[k], 0.01 * eta[k]) << "E = " << E[k];
    EXPECT_NEAR(p.dt_eq26, dt[k], 0.01 * dt[k]) << "E = " << E[k];
  }
}

TEST(ElasticParams, DerivedRelations) {
  ElasticInputs in;
  in.E = 750 * kKgfPerCm2;
  const ElasticParams p = elastic_params(in);
  EXPECT_DOUBLE_EQ(p.ks, 0.25 * p.kn);                 // (24)
  EXPECT_DOUBLE_EQ(p.eta_s, 0.5 * p.eta_n);            // (25b), sqrt(0.25)
  EXPECT_NEAR(p.mass, 2.65 * M_PI, 1e-12);
  // (23) closed form against q / delta.
  const double closed = M_PI * in.E / (2 * (1 - in.nu * in.nu) * (2.0 / 3.0 + 2 * std::log(4 * in.r / p.b)));
  EXPECT_NEAR(p.kn, closed, 1e-9 * closed);
}
