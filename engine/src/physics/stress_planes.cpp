#include "physics/stress_planes.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "physics/contact_frame.hpp"

namespace dem {

namespace {
// Force on the upper disc of a cut pair i-j from the lower one, given the total normal and shear
// forces of the contact and the unit normal from i to j: on j it is f_n n + f_s t, t = (-ny, nx).
void cut_force(double fn, double fs, double nx, double ny, bool j_above, double& fx, double& fy) {
  const ContactForce j = contact_force(-fn, -fs, {nx, ny});  // on j: (15) of the opposite forces
  fx = j_above ? j.x : -j.x;
  fy = j_above ? j.y : -j.y;
}
}  // namespace

std::vector<PlaneStress> plane_stresses(const World& w, const std::vector<double>& plane_y, double width) {
  const Discs& d = w.discs;
  std::vector<PlaneStress> out(plane_y.size());
  for (std::size_t k = 0; k < plane_y.size(); ++k) out[k].y = plane_y[k];
  // Positions of the last force computation: eqs. 18/19 move the discs after it, Verlet before.
  const bool moved = !verlet_family(w.scheme);
  std::vector<double> px(d.x), py(d.y);
  if (moved) {
    const World::Increments u = w.increments();
    for (std::size_t i = 0; i < d.size(); ++i) {
      px[i] -= u.x[i] * u.factor;
      py[i] -= u.y[i] * u.factor;
    }
  }
  // Cut contacts: accumulate the force on the part above from below (then reverse it).
  auto add_cut = [&](int i, int j, double fn, double fs) {
    const double dx = px[j] - px[i], dy = py[j] - py[i];
    const double R = std::hypot(dx, dy);
    if (!(R > 0)) return;
    for (PlaneStress& p : out) {
      const bool i_below = py[i] < p.y, j_below = py[j] < p.y;
      if (i_below == j_below) continue;
      double fx, fy;
      cut_force(fn, fs, dx / R, dy / R, i_below, fx, fy);
      p.fx -= fx;  // on the part below from the part above
      p.fy -= fy;
      ++p.contacts;
    }
  };
  if (!w.pair_forces_current()) throw std::logic_error("plane stresses: the pair forces of this step were not recorded");
  w.each_recorded_pair([&](int i, int j, double fn, double fs) {  // the pairs that touched in the last force pass
    const double dx = px[j] - px[i], dy = py[j] - py[i];
    const double sum = d.r(i) + d.r(j);
    if (dx * dx + dy * dy > sum * sum) return;  // (as they must, at the positions of that pass)
    if (fn == 0 && fs == 0) return;
    add_cut(i, j, fn, fs);
  });
  for (const Bond& b : w.bonds) add_cut(b.i, b.j, b.fn, b.fs);

  // Cross-check: the part above is held by the cut, so the cut force on it equals
  // sum(m a) - gravity - (wall and plate forces on it).
  for (PlaneStress& p : out) {
    double gxs = 0, gys = 0;  // on the part above: gravity, walls, plate
    double max = 0, may = 0;  // sum of m a (the resultants of the last force computation)
    for (std::size_t i = 0; i < d.size(); ++i) {
      if (!(py[i] > p.y)) continue;
      gxs += d.mass(i) * w.gx;
      gys += d.mass(i) * w.gy;
      max += d.fx[i];
      may += d.fy[i];
    }
    for (const WallContact& c : w.neighbors.walls) {
      if (!c.touching || !(py[c.i] > p.y)) continue;
      const ContactForce f = contact_force(c.fn, c.fs, {c.nx, c.ny});  // on the disc
      gxs += f.x;
      gys += f.y;
    }
    // Force on the part below from the part above = (gxs, gys) - (max, may).
    p.sigma = -p.fy / width;
    p.tau = p.fx / width;
    p.sigma_check = -gys / width;
    p.tau_check = gxs / width;
    p.sigma_inertia = may / width;
    p.tau_inertia = -max / width;
  }
  return out;
}

std::vector<int> assign_rows(const Discs& d, double gap, int& n_rows) {
  const std::size_t n = d.size();
  std::vector<int> order(n), row(n, 0);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return d.y[a] < d.y[b]; });
  n_rows = n ? 1 : 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0 && d.y[order[k]] - d.y[order[k - 1]] > gap) ++n_rows;
    row[order[k]] = n_rows - 1;
  }
  return row;
}

std::vector<double> planes_between_rows(const Discs& d, const std::vector<int>& row, int n_rows) {
  std::vector<double> sum(n_rows, 0), cnt(n_rows, 0);
  for (std::size_t i = 0; i < d.size(); ++i) {
    sum[row[i]] += d.y[i];
    cnt[row[i]] += 1;
  }
  std::vector<double> planes;
  for (int k = 0; k + 1 < n_rows; ++k)
    planes.push_back(0.5 * (sum[k] / cnt[k] + sum[k + 1] / cnt[k + 1]));
  return planes;
}

}  // namespace dem
