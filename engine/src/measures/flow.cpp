#include "measures/flow.hpp"

#include <algorithm>
#include <limits>

#include "physics/discs.hpp"

namespace dem {

namespace {

// Top of the fill in a column [x0, x1]: the highest disc top among discs inside the silo.
double surface(const Discs& d, double x0, double x1, double floor) {
  double top = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < d.size(); ++i)
    if (d.x[i] >= x0 && d.x[i] < x1 && d.y[i] > floor) top = std::max(top, d.y[i] + d.r(i));
  return top;
}

}  // namespace

double flow_rate(const std::vector<Removal>& removals) {
  std::vector<double> t, m;
  double cum = 0;
  for (const Removal& r : removals) {
    if (r.keystone) continue;
    cum += r.mass;
    t.push_back(r.t);
    m.push_back(cum);
  }
  if (t.size() < 10) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t a = 4;
  double st = 0, sm = 0, stt = 0, stm = 0, k = 0;
  for (std::size_t i = a; i < t.size(); ++i) {
    st += t[i]; sm += m[i]; stt += t[i] * t[i]; stm += t[i] * m[i]; k += 1;
  }
  const double den = k * stt - st * st;
  return den > 0 ? (k * stm - st * sm) / den : std::numeric_limits<double>::quiet_NaN();
}

void surfaces(const Discs& d, double x_left, double xc, double x_right, double floor, double col, double s[3]) {
  s[0] = surface(d, x_left, x_left + col, floor);
  s[1] = surface(d, xc - 0.5 * col, xc + 0.5 * col, floor);
  s[2] = surface(d, x_right - col, x_right + 1e-12, floor);
}

}  // namespace dem
