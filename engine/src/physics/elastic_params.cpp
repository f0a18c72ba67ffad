#include "physics/elastic_params.hpp"

#include <cmath>

namespace dem {

ElasticParams elastic_params(const ElasticInputs& in) {
  const double pi = M_PI;
  const double c = (1.0 - in.nu * in.nu) / in.E;
  ElasticParams p{};
  const double r1 = in.r, r2 = in.r;
  p.b = std::sqrt(8.0 / pi * (r1 * r2 / (r1 + r2)) * c * in.q);                            // (22b)
  p.delta = 2.0 * c * in.q / pi * (2.0 / 3.0 + std::log(4 * r1 / p.b) + std::log(4 * r2 / p.b));  // (22a)
  p.kn = in.q / p.delta;  // (23): pi E / (2 (1-nu^2) (2/3 + 2 ln(4r/b)))
  p.ks = in.s * p.kn;     // (24)
  p.mass = in.rho * pi * in.r * in.r;
  p.eta_n = 2.0 * std::sqrt(p.mass * p.kn);  // (20), (25a)
  p.eta_s = p.eta_n * std::sqrt(in.s);       // (25b)
  p.dt_eq26 = p.eta_n / p.kn;                // (26)
  p.dt_eq21 = 2.0 * std::sqrt(p.mass / p.kn);  // (21), bracket restored
  return p;
}

}  // namespace dem
