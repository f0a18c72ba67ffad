// The discs put in cell order (disc_order.hpp says when): every per-disc array, the lists with
// their history, the bonds and the recorded totals follow the discs, so the next force pass
// computes the same contacts with the same history; only the order of each disc's sums changes
// (its pairs are added in the new list order), a round-off difference. Ids travel with the
// discs: the user's order is theirs (Discs::by_id).
#include <algorithm>
#include <type_traits>

#include "physics/world.hpp"

namespace dem {

void World::check_disc_order() {
  if (disc_order != DiscOrder::automatic || discs.size() < DiscOrderRule::kMinDiscs) return;
  const OrderGrid g = order_grid(discs, neighbors.skin, neighbors.min_cell);
  if (disc_order_degraded(neighbors.pairs, discs, g.ny)) resort_discs();
}

void World::resort_discs() {
  Discs& d = discs;
  const std::size_t n = d.size();
  // order[s]: the disc to put at s
  const std::vector<int> order = cell_order(d, order_grid(d, neighbors.skin, neighbors.min_cell));
  bool same = true;
  for (std::size_t s = 0; s < n && same; ++s) same = order[s] == static_cast<int>(s);
  if (same) return;
  std::vector<int> new_index(n);
  for (std::size_t s = 0; s < n; ++s) new_index[order[s]] = static_cast<int>(s);
  d.make_ids();
  const auto put = [&](auto& v) {
    if (v.empty()) return;  // an array this scene does not keep (kinds, angle, eq. 19's increments)
    std::remove_reference_t<decltype(v)> t(v.size());
    for (std::size_t s = 0; s < n; ++s) t[s] = v[order[s]];
    v.swap(t);
  };
  put(d.kind); put(d.id);
  put(d.x); put(d.y); put(d.phi);
  put(d.vx); put(d.vy); put(d.omega);
  put(d.dux); put(d.duy); put(d.dphi);
  put(d.fx); put(d.fy); put(d.torque);
  pair_totals.renumber(neighbors.pairs, new_index);  // over the list as it was
  onset_normals.renumber(new_index);
  neighbors.renumber(new_index);
  for (Bond& b : bonds) {  // a bond whose discs swap order swaps its arms (its forces are symmetric)
    const int i = new_index[b.i], j = new_index[b.j];
    if (i > j) std::swap(b.ai, b.aj);
    b.i = std::min(i, j);
    b.j = std::max(i, j);
  }
  std::sort(bonds.begin(), bonds.end(), [](const Bond& a, const Bond& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  cross_ok_ = false;
  balance_blocks();  // the blocks' work moved with the discs
  ++resorts;
}

}  // namespace dem
