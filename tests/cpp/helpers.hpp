// Small worlds built in code for the physics tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "physics/world.hpp"

namespace dem::testing {

// One material (index 0) for discs; walls use material 1. Both pairs get `p` unless given.
inline World make_world(const PairProps& p, ContactOptions opt, Scheme scheme, double dt,
                        double gy = 0.0, const PairProps* wall = nullptr) {
  World w;
  w.n_materials = 2;
  w.props = {p, wall ? *wall : p, wall ? *wall : p, wall ? *wall : p};
  w.options = opt;
  w.scheme = scheme;
  w.dt = dt;
  w.gx = 0;
  w.gy = gy;
  return w;
}

// Linear spring-dashpot with damping ratio zeta for effective mass m_eff.
inline PairProps linear(double kn, double zeta, double m_eff, double mu = 0.0, double ks = 0.0, double eta_s = 0.0) {
  PairProps p;
  p.kn = kn;
  p.eta_n = 2 * zeta * std::sqrt(m_eff * kn);
  p.ks = ks;
  p.eta_s = eta_s;
  p.mu = mu;
  return p;
}

// The law LIGGGHTS and YADE share (compare/): overlap spring, no tension and Coulomb cap on the
// totals, the contact point's arms.
inline ContactOptions shared_law() {
  ContactOptions o;
  o.normal_spring = NormalSpring::overlap;
  o.no_tension = NoTension::total;
  o.friction_cap = FrictionCap::total;
  o.lever_arm = LeverArm::contact_point;
  return o;
}

// FNV-1a over the bytes of every disc's position, velocity and spin: two runs' states compared
// bit for bit.
inline std::uint64_t state_hash(const Discs& d) {
  std::uint64_t h = 1469598103934665603ull;
  for (const auto* v : {&d.x, &d.y, &d.vx, &d.vy, &d.omega})
    for (double x : *v) {
      unsigned char b[sizeof x];
      std::memcpy(b, &x, sizeof x);
      for (unsigned char c : b) h = (h ^ c) * 1099511628211ull;
    }
  return h;
}

constexpr Scheme kSchemes[3] = {Scheme::paper_eq18, Scheme::paper_eq19, Scheme::velocity_verlet};

}  // namespace dem::testing
