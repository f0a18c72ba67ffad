#include "physics/clusters.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dem {

const char* to_string(BondSet b) { return b == BondSet::all ? "all" : "touching"; }

std::vector<int> cluster_of_discs(std::size_t n, const ClusterSpec& spec) {
  std::vector<int> of(n, -1);
  for (std::size_t c = 0; c < spec.members.size(); ++c)
    for (int i : spec.members[c])
      if (i >= 0 && static_cast<std::size_t>(i) < n) of[i] = static_cast<int>(c);
  return of;
}

std::vector<Bond> make_bonds(const Discs& d, const ClusterSpec& spec) {
  const std::size_t n = d.size();
  std::vector<int> owner(n, -1);
  std::vector<Bond> bonds;
  for (std::size_t c = 0; c < spec.members.size(); ++c) {
    const auto& m = spec.members[c];
    const std::string where = "cluster " + std::to_string(c);
    if (m.size() < 2) throw std::invalid_argument(where + ": a cluster needs at least two discs");
    for (int i : m) {
      if (i < 0 || static_cast<std::size_t>(i) >= n)
        throw std::invalid_argument(where + ": disc index " + std::to_string(i) + " is out of range [0, " +
                                    std::to_string(n) + ")");
      if (owner[i] >= 0)
        throw std::invalid_argument(where + ": disc " + std::to_string(i) + " is already in cluster " +
                                    std::to_string(owner[i]));
      owner[i] = static_cast<int>(c);
    }
    // Union-find over the bonded pairs: a cluster must hold together.
    std::vector<int> parent(m.size());
    for (std::size_t a = 0; a < m.size(); ++a) parent[a] = static_cast<int>(a);
    auto root = [&](int a) {
      while (parent[a] != a) a = parent[a] = parent[parent[a]];
      return a;
    };
    for (std::size_t a = 0; a < m.size(); ++a)
      for (std::size_t b = a + 1; b < m.size(); ++b) {
        const int i = std::min(m[a], m[b]), j = std::max(m[a], m[b]);
        const double R = std::hypot(d.x[j] - d.x[i], d.y[j] - d.y[i]);
        const double sum = d.r(i) + d.r(j);
        if (spec.bonds == BondSet::touching && R - sum > spec.touch_tolerance) continue;
        if (!(R > 0)) throw std::invalid_argument(where + ": discs " + std::to_string(i) + " and " +
                                                  std::to_string(j) + " are at the same place");
        Bond bd;
        bd.i = i;
        bd.j = j;
        bd.rest = R;
        const double stretch = std::max(1.0, R / sum);
        bd.ai = d.r(i) * stretch;
        bd.aj = d.r(j) * stretch;
        bonds.push_back(bd);
        parent[root(static_cast<int>(a))] = root(static_cast<int>(b));
      }
    for (std::size_t a = 1; a < m.size(); ++a)
      if (root(static_cast<int>(a)) != root(0))
        throw std::invalid_argument(where + ": not connected by touching pairs (gap > touch_tolerance = " +
                                    std::to_string(spec.touch_tolerance) + " cm); use bonds = \"all\"");
  }
  std::sort(bonds.begin(), bonds.end(), [](const Bond& a, const Bond& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  return bonds;
}

double max_bond_strain(const Discs& d, const std::vector<Bond>& bonds) {
  double worst = 0;
  for (const Bond& b : bonds) {
    const double R = std::hypot(d.x[b.j] - d.x[b.i], d.y[b.j] - d.y[b.i]);
    worst = std::max(worst, std::abs(R - b.rest) / b.rest);
  }
  return worst;
}

}  // namespace dem
