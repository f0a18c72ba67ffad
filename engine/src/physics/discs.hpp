// Disc state as flat arrays (structure of arrays): the step streams through these.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <numeric>
#include <vector>

namespace dem {

// The constants of a kind of disc: discs of one radius, density and material share one entry,
// so a scene of a few kinds spends only a 4-byte kind index per disc on them (36 bytes a disc as
// per-disc arrays, a sixth of a million-disc run). A scene whose every disc differs has one kind
// a disc.
struct DiscKinds {
  std::vector<double> r;            // radius [cm]
  std::vector<double> mass;         // rho pi r^2 [g per cm of thickness]
  std::vector<double> inv_mass;     // 1/m (0: a disc held in place, Discs::hold)
  std::vector<double> inv_inertia;  // 1/I, I = m r^2 / 2
  std::vector<int> material;        // index into the scene's materials
  std::size_t size() const { return r.size(); }
};

// Discs leaving the arrays (an outlet takes a few a step): their indices, sorted, with no mask
// or map the size of all discs (a 4-byte map a disc made each removal step the peak of a
// million-disc discharge). The new index of disc k is k less the removed discs below it.
struct RemovedDiscs {
  std::vector<int> sorted;  // increasing, no repeats, each in [0, number of discs)
  int new_index(int k) const {  // -1 for a removed disc
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), k);
    return it != sorted.end() && *it == k ? -1 : k - static_cast<int>(it - sorted.begin());
  }
  // Drops the entries of the removed discs from a per-disc array (order kept).
  template <class V>
  void compact(V& v) const {
    std::size_t k = 0, g = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (g < sorted.size() && static_cast<std::size_t>(sorted[g]) == i) {
        ++g;
        continue;
      }
      v[k++] = v[i];
    }
    v.resize(k);
  }
};

struct Discs {
  DiscKinds kinds;
  // Index into kinds; empty while there is one kind (every disc of kind 0): a scene of one kind
  // spends nothing on it (4 bytes a disc, 2 % of a million-disc run). Read it through kind_at.
  std::vector<int> kind;
  // Stable ids (they survive removals); empty while disc i has id i (no disc has left): a run
  // that removes none spends nothing on them (4 bytes a disc). Read them through id_at.
  std::vector<int> id;
  // Kinematics.
  std::vector<double> x, y;            // position [cm]
  std::vector<double> phi;             // rotation [rad], counter-clockwise: only with World::rotation_angle
  std::vector<double> vx, vy, omega;   // velocities
  std::vector<double> dux, duy, dphi;  // last increments du, dv, dphi: eq. 19 only (World::increments)
  // Resultants of eq. (15), gravity included.
  std::vector<double> fx, fy, torque;

  std::size_t size() const { return x.size(); }
  int kind_at(std::size_t i) const { return kind.empty() ? 0 : kind[i]; }
  int id_at(std::size_t i) const { return id.empty() ? static_cast<int>(i) : id[i]; }
  // The ids as an array (before a removal or a re-sort breaks id == index).
  void make_ids() {
    if (!id.empty()) return;
    id.resize(x.size());
    std::iota(id.begin(), id.end(), 0);
    id_end_ = static_cast<int>(x.size());
  }
  // The id the next added disc gets: one past the largest (ids only grow; after a re-sort the
  // last disc need not hold the largest). Call after ids are set from outside (a state read).
  void count_ids() {
    id_end_ = 0;
    for (int v : id) id_end_ = std::max(id_end_, v + 1);
  }
  // The indices of the discs in increasing id order: the user's order, in which every output
  // lists the discs (the arrays themselves may be in cell order, World::resort_discs). Empty
  // while the discs already are in that order (no re-sort yet): callers read index k then.
  std::vector<int> by_id() const {
    bool sorted = true;
    for (std::size_t i = 1; i < id.size() && sorted; ++i) sorted = id[i] > id[i - 1];
    if (sorted) return {};
    std::vector<int> order(id.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return id[a] < id[b]; });
    return order;
  }
  // Disc i's constants.
  double r(std::size_t i) const { return kinds.r[kind_at(i)]; }
  double mass(std::size_t i) const { return kinds.mass[kind_at(i)]; }
  double inv_mass(std::size_t i) const { return kinds.inv_mass[kind_at(i)]; }
  double inv_inertia(std::size_t i) const { return kinds.inv_inertia[kind_at(i)]; }
  int material(std::size_t i) const { return kinds.material[kind_at(i)]; }

  // Room for n discs exactly (a fill of known count): no doubling slack, about 5 % at 1M discs.
  // The kind array gets its room when a second kind appears.
  void reserve(std::size_t n) {
    for (auto* v : {&x, &y, &phi, &vx, &vy, &omega, &dux, &duy, &dphi, &fx, &fy, &torque}) v->reserve(n);
    room_ = n;
  }
  // Room for the positions, ids and kinds of n discs only (a contact search over discs that are
  // not stepped, add_position).
  void reserve_positions(std::size_t n) {
    x.reserve(n);
    y.reserve(n);
    room_ = n;
  }
  // Frees the kind and id arrays where they hold what kind_at and id_at give without them (a
  // state read back, whose file holds both whole).
  void drop_derivable_arrays() {
    if (kinds.size() <= 1) std::vector<int>().swap(kind);
    for (std::size_t i = 0; i < id.size(); ++i)
      if (id[i] != static_cast<int>(i)) return;
    std::vector<int>().swap(id);
  }
  void add(double px, double py, double radius, double density, int mat) {
    add_position(px, py, radius, density, mat);
    for (auto* v : {&phi, &vx, &vy, &omega, &dux, &duy, &dphi, &fx, &fy, &torque}) v->push_back(0);
  }
  // Kind, id and position only (no velocities, forces or angle): for a contact search over discs
  // that are not stepped (the scene's check of its initial discs); add() goes on from here.
  void add_position(double px, double py, double radius, double density, int mat) {
    const double m = density * 3.14159265358979323846 * radius * radius;
    set_kind(x.size(), kind_of(radius, m, 1.0 / m, 2.0 / (m * radius * radius), mat));
    if (!id.empty()) id.push_back(id_end_++);  // after removals or a re-sort: the next id (ids only grow)
    x.push_back(px);
    y.push_back(py);
  }
  // Disc i no longer moves under forces: a kind of its own, with zero inverse mass and inertia.
  void hold(std::size_t i) {
    set_kind(i, kind_of(r(i), mass(i), 0.0, 0.0, material(i)));
  }
  // Frees the index add() searches kinds with (the world calls it once the discs are in).
  void forget_kind_index() { std::vector<std::size_t>().swap(slots_); }

 private:
  std::size_t room_ = 0;  // discs reserve() made room for (the kind array's, when it is made)
  int id_end_ = 0;        // with an id array: one past the largest id (count_ids)
  // Disc i (i == size(): the disc being added) is of kind k; the array is made, all zeros, when
  // the first disc of another kind than 0 comes.
  void set_kind(std::size_t i, int k) {
    if (kind.empty() && k != 0) {
      kind.reserve(std::max(room_, i + 1));
      kind.assign(x.size(), 0);
    }
    if (kind.empty()) return;
    if (i == kind.size()) kind.push_back(k);
    else kind[i] = k;
  }
  // Open-addressing hash of the kinds by their constants' bits; empty until add() needs it.
  std::vector<std::size_t> slots_;  // kind + 1, 0 empty
  static std::size_t bits(double v) {
    std::size_t b;
    static_assert(sizeof b == sizeof v);
    std::memcpy(&b, &v, sizeof b);
    return b;
  }
  bool same(std::size_t k, double radius, double m, double im, double ii, int mat) const {
    return bits(kinds.r[k]) == bits(radius) && bits(kinds.mass[k]) == bits(m) && bits(kinds.inv_mass[k]) == bits(im) &&
           bits(kinds.inv_inertia[k]) == bits(ii) && kinds.material[k] == mat;
  }
  std::size_t slot_of(double radius, double m, double im, double ii, int mat) const {
    std::size_t h = bits(radius) * 0x9E3779B97F4A7C15ull ^ bits(m) * 0xC2B2AE3D27D4EB4Full ^
                    bits(im) * 0x165667B19E3779F9ull ^ bits(ii) * 0x27D4EB2F165667C5ull ^ static_cast<std::size_t>(mat);
    h ^= h >> 29;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t s = h & mask;; s = (s + 1) & mask)
      if (slots_[s] == 0 || same(slots_[s] - 1, radius, m, im, ii, mat)) return s;
  }
  int kind_of(double radius, double m, double im, double ii, int mat) {
    if (slots_.size() < 2 * kinds.size() + 2) {  // (re)build at a load of at most 1/2
      std::size_t cap = 16;
      while (cap < 4 * kinds.size() + 4) cap *= 2;
      slots_.assign(cap, 0);
      for (std::size_t k = 0; k < kinds.size(); ++k)
        slots_[slot_of(kinds.r[k], kinds.mass[k], kinds.inv_mass[k], kinds.inv_inertia[k], kinds.material[k])] = k + 1;
    }
    const std::size_t s = slot_of(radius, m, im, ii, mat);
    if (slots_[s] == 0) {
      kinds.r.push_back(radius); kinds.mass.push_back(m); kinds.inv_mass.push_back(im);
      kinds.inv_inertia.push_back(ii); kinds.material.push_back(mat);
      slots_[s] = kinds.size();
    }
    return static_cast<int>(slots_[s] - 1);
  }
};

}  // namespace dem
