// The contact law of eqs. (6)-(14) on single calls: no tension, Coulomb cap, dashpot switch-off.
#include <gtest/gtest.h>

#include "physics/contact_law.hpp"

using namespace dem;

namespace {
PairProps props() {
  PairProps p;
  p.kn = 1000;
  p.ks = 250;
  p.eta_n = 10;
  p.eta_s = 5;
  p.mu = 0.5;
  return p;
}
constexpr double kInvDt = 100.0;  // dt = 0.01
}  // namespace

TEST(ContactLaw, IncrementalSpringsAndDashpotsAsWritten) {
  const PairProps p = props();
  double en = 20, es = 1, fn, fs;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.5, 0.01, 0.002, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(en, 20 + 1000 * 0.01);           // (7a)
  EXPECT_DOUBLE_EQ(fn, en + 10 * 0.01 * kInvDt);    // (9) with (7b)
  EXPECT_DOUBLE_EQ(es, 1 + 250 * 0.002);            // (11a)
  EXPECT_DOUBLE_EQ(fs, es + 5 * 0.002 * kInvDt);    // (14) with (11b)
}

TEST(ContactLaw, OverlapSpringUsesTotalOverlap) {
  const PairProps p = props();
  double en = 999, es = 0, fn, fs;
  contact_law<NormalSpring::overlap, NoTension::total, FrictionCap::total>(p, 0.03, 0.0, 0.0, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(en, 1000 * 0.03);
  EXPECT_DOUBLE_EQ(fn, 30);
}

TEST(ContactLaw, NoTensionOnElasticPartZeroesEverything) {
  const PairProps p = props();
  double en = 5, es = 2, fn, fs;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.0, -0.01, 0.01, kInvDt, en, es, fn, fs);
  EXPECT_EQ(en, 0);  // (8)
  EXPECT_EQ(fn, 0);
  EXPECT_EQ(es, 0);  // (12)
  EXPECT_EQ(fs, 0);
}

TEST(ContactLaw, ElasticRuleLetsTheDashpotPull) {
  // Eq. (8) tests e_n only: a separating contact with e_n >= 0 can carry a tensile total force.
  const PairProps p = props();
  double en = 10, es = 0, fn, fs;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.0, -0.005, 0, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(en, 5);
  EXPECT_DOUBLE_EQ(fn, 5 - 10 * 0.005 * kInvDt);  // = 0 exactly here...
  double en2 = 10, es2 = 0, fn2, fs2;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.0, -0.008, 0, kInvDt, en2, es2, fn2, fs2);
  EXPECT_LT(fn2, 0);  // ...and tensile here: 2 - 8
}

TEST(ContactLaw, TotalRuleClampsTheTotalForce) {
  const PairProps p = props();
  double en = 10, es = 0, fn, fs;
  contact_law<NormalSpring::incremental, NoTension::total, FrictionCap::total>(p, 0.0, -0.008, 0, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(en, 2);
  EXPECT_EQ(fn, 0);
}

TEST(ContactLaw, OverlapRuleAllowsViscousPull) {
  const PairProps p = props();
  double en = 0, es = 0, fn, fs;
  contact_law<NormalSpring::overlap, NoTension::overlap, FrictionCap::total>(p, 0.002, -0.008, 0, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(fn, 2 - 8);
}

TEST(ContactLaw, CoulombCapOnElasticNormalForceSwitchesDashpotOff) {
  const PairProps p = props();
  double en = 100, es = 45, fn, fs;
  // e_s = 45 + 250 * 0.04 = 55 > mu e_n = 50 -> capped at 50, no dashpot (13a), (13b).
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.1, 0.0, 0.04, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(es, 50);
  EXPECT_DOUBLE_EQ(fs, 50);
  // Negative direction: sign kept.
  double en2 = 100, es2 = -45, fn2, fs2;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.1, 0.0, -0.04, kInvDt, en2, es2, fn2, fs2);
  EXPECT_DOUBLE_EQ(es2, -50);
  EXPECT_DOUBLE_EQ(fs2, -50);
  // Below the cap the dashpot acts.
  double en3 = 100, es3 = 0, fn3, fs3;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.1, 0.0, 0.01, kInvDt, en3, es3, fn3, fs3);
  EXPECT_DOUBLE_EQ(es3, 2.5);
  EXPECT_DOUBLE_EQ(fs3, 2.5 + 5 * 0.01 * kInvDt);
}

TEST(ContactLaw, CoulombCapOnTotalNormalForce) {
  const PairProps p = props();
  // e_n = 100, d_n = 10 * 0.02 * 100 = 20: cap mu |f_n| = 60 (elastic rule would give 50).
  double en = 100, es = 55, fn, fs;
  contact_law<NormalSpring::incremental, NoTension::total, FrictionCap::total>(p, 0.1, 0.0 + 0.0, 0.0, kInvDt, en, es, fn, fs);
  EXPECT_DOUBLE_EQ(es, 50);  // f_n = 100 here, cap 50
  double en2 = 100 - 1000 * 0.0, es2 = 55, fn2, fs2;
  const double du_n = 0.02;
  en2 = 100 - 1000 * du_n;  // so that e_n returns to 100 after the increment
  contact_law<NormalSpring::incremental, NoTension::total, FrictionCap::total>(p, 0.1, du_n, 0.0, kInvDt, en2, es2, fn2, fs2);
  EXPECT_DOUBLE_EQ(en2, 100);
  EXPECT_DOUBLE_EQ(fn2, 120);
  EXPECT_DOUBLE_EQ(es2, 55);  // below mu f_n = 60: not capped
  double en3 = 100 - 1000 * du_n, es3 = 55, fn3, fs3;
  contact_law<NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic>(p, 0.1, du_n, 0.0, kInvDt, en3, es3, fn3, fs3);
  EXPECT_DOUBLE_EQ(es3, 50);  // the paper's cap mu e_n = 50
}
