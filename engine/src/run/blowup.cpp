#include "run/blowup.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "physics/parallel.hpp"
#include "physics/world.hpp"

namespace dem {

double potential_energy(const World& w) {
  const Discs& d = w.discs;
  const long n = static_cast<long>(d.size());
  return -parallel_sum(n, w.threads_for(static_cast<int>(n)),
                       [&](long i) { return d.mass(i) * (w.gx * d.x[i] + w.gy * d.y[i]); });
}

double elastic_energy(const World& w) {
  const Discs& d = w.discs;
  double e = 0;
  auto spring = [](double f, double k) { return k > 0 ? 0.5 * f * f / k : 0.0; };
  for (const PairContact& c : w.neighbors.pairs) {
    const PairProps& p = w.pair(d.material(c.i), d.material(c.j));
    e += spring(c.en, p.kn) + spring(c.es, p.ks);
  }
  const int nw = static_cast<int>(w.geometry.walls.size());
  for (const WallContact& c : w.neighbors.walls) {
    const int km = c.k < nw ? w.geometry.walls[c.k].material : w.geometry.points[c.k - nw].material;
    const PairProps& p = w.props[d.material(c.i) * w.n_materials + km];
    e += spring(c.en, p.kn) + spring(c.es, p.ks);
  }
  for (const Bond& b : w.bonds) {
    const PairProps& p = w.pair(d.material(b.i), d.material(b.j));
    e += spring(b.en, p.kn) + spring(b.es, p.ks);
  }
  return e;
}

void EnergyWatch::start(const World& w, double max_gain) {
  gain = max_gain;
  active = w.moving.empty();  // moving walls and plates feed energy in: no budget to hold
  const Discs& d = w.discs;
  if (d.size() == 0) { active = false; return; }
  const double ke = w.kinetic_energy(), el = elastic_energy(w);
  budget = ke + potential_energy(w) + el;
  // The energy gravity can release: all discs falling through the packing's height span.
  const double g = std::hypot(w.gx, w.gy);
  double lo = 1e300, hi = -1e300, mass = 0, rmax = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double h = g > 0 ? -(w.gx * d.x[i] + w.gy * d.y[i]) / g : 0;  // height along -g
    lo = std::min(lo, h);
    hi = std::max(hi, h);
    mass += d.mass(i);
    rmax = std::max(rmax, d.r(i));
  }
  scale = ke + el + mass * g * (hi - lo + 2 * rmax);
  if (!(scale > 0) || !std::isfinite(scale)) active = false;  // nothing to release: no criterion
}

std::string EnergyWatch::check(const World& w, Units units) const {
  if (!active) return "";
  const double ke = w.kinetic_energy();
  const double now = ke + potential_energy(w);
  if (now - budget <= gain * scale) return "";
  const Discs& d = w.discs;
  std::size_t fast = 0;
  double vmax2 = -1;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double v2 = d.vx[i] * d.vx[i] + d.vy[i] * d.vy[i];
    if (v2 > vmax2) { vmax2 = v2; fast = i; }
  }
  const UnitNames u = unit_names(units);
  std::ostringstream os;
  os.precision(4);
  os << "energy created without a source: kinetic + potential energy " << now << " exceeds the start budget "
     << budget << " (kinetic + potential + elastic) by " << (now - budget) << ' ' << u.energy << ", more than end.max_energy_gain "
     << gain << " x scale " << scale << "; kinetic energy " << ke << "; fastest disc id " << d.id_at(fast) << " at ("
     << d.x[fast] << ", " << d.y[fast] << ") " << u.length << ", speed " << std::sqrt(vmax2) << ' ' << u.velocity
     << ", omega " << d.omega[fast]
     << " 1/s; at t = " << w.time << " s (step " << w.steps << ")";
  return os.str();
}

}  // namespace dem
