#include "physics/pair_totals.hpp"

#include <algorithm>

#include <stdexcept>

namespace dem {

void PairTotals::start(std::size_t count, std::size_t list_size) {
  std::vector<std::array<int, 2>>().swap(ij_);
  if (count > f_.capacity()) std::vector<Force>().swap(f_);  // a larger count: never both held
  f_.resize(count);
  bits_.assign((list_size + 63) / 64, 0);
  list_size_ = list_size;
  detached_ = false;
}

void PairTotals::clear() {
  std::vector<Force>().swap(f_);
  std::vector<std::uint64_t>().swap(bits_);
  std::vector<std::array<int, 2>>().swap(ij_);
  list_size_ = 0;
  detached_ = false;
}

void PairTotals::check_list(const std::vector<PairContact>& pairs) const {
  // Every change of the list detaches or compacts the totals first; a list of another size here
  // is a bug (bits read against the wrong pairs), not a state to go on from.
  if (pairs.size() != list_size_)
    throw std::logic_error("recorded pair totals: the pair list changed since the recorded pass");
}

void PairTotals::detach(const std::vector<PairContact>& pairs) {
  if (detached_ || !allocated()) return;
  std::vector<std::array<int, 2>> ij;
  ij.reserve(f_.size());
  each(pairs, [&](int i, int j, double, double) { ij.push_back({i, j}); });
  ij_.swap(ij);
  std::vector<std::uint64_t>().swap(bits_);
  list_size_ = 0;
  detached_ = true;
}

void PairTotals::renumber(const std::vector<PairContact>& pairs, const std::vector<int>& new_index) {
  detach(pairs);
  if (!detached_) return;  // nothing recorded
  std::vector<std::size_t> at(f_.size());
  for (std::size_t r = 0; r < f_.size(); ++r) {
    const int i = new_index[ij_[r][0]], j = new_index[ij_[r][1]];
    ij_[r] = {std::min(i, j), std::max(i, j)};
    at[r] = r;
  }
  std::sort(at.begin(), at.end(), [&](std::size_t a, std::size_t b) { return ij_[a] < ij_[b]; });
  std::vector<Force> f(f_.size());
  std::vector<std::array<int, 2>> ij(ij_.size());
  for (std::size_t r = 0; r < at.size(); ++r) {
    f[r] = f_[at[r]];
    ij[r] = ij_[at[r]];
  }
  f_.swap(f);
  ij_.swap(ij);
}

void PairTotals::compact(const std::vector<PairContact>& pairs, const RemovedDiscs& removed) {
  if (detached_) {
    std::size_t o = 0;
    for (std::size_t r = 0; r < f_.size(); ++r) {
      const int i = removed.new_index(ij_[r][0]), j = removed.new_index(ij_[r][1]);
      if (i < 0 || j < 0) continue;
      ij_[o] = {i, j};
      f_[o++] = f_[r];
    }
    ij_.resize(o);
    f_.resize(o);
    return;
  }
  if (!allocated()) return;  // nothing recorded
  check_list(pairs);
  // The pairs Neighbors::compact keeps, in order: their bits move down to their new places, and
  // the totals of the touching ones with them, both in place (a new place o is never after the
  // old one p, whose bit is read before bit o is written).
  std::size_t o = 0, r = 0, nr = 0;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const bool touched = bit(p);
    if (removed.new_index(pairs[p].i) >= 0 && removed.new_index(pairs[p].j) >= 0) {
      const std::uint64_t mask = std::uint64_t{1} << (o & 63);
      bits_[o >> 6] = touched ? bits_[o >> 6] | mask : bits_[o >> 6] & ~mask;
      if (touched) f_[nr++] = f_[r];
      ++o;
    }
    r += touched;
  }
  bits_.resize((o + 63) / 64);
  if (o & 63) bits_.back() &= (std::uint64_t{1} << (o & 63)) - 1;  // no bits past the list's end
  f_.resize(nr);
  list_size_ = o;
}

void PairTotals::start_detached(std::size_t count) {
  clear();
  f_.reserve(count);
  ij_.reserve(count);
  detached_ = true;
}

void PairTotals::assign(const std::vector<PairForce>& records) {
  start_detached(records.size());
  for (const PairForce& q : records) push(q);
}

std::vector<PairForce> PairTotals::records(const std::vector<PairContact>& pairs) const {
  std::vector<PairForce> out;
  out.reserve(f_.size());
  each(pairs, [&](int i, int j, double fn, double fs) { out.push_back(PairForce{i, j, fn, fs}); });
  return out;
}

const PairTotals::Force* PairTotals::at(const std::vector<PairContact>& pairs, std::size_t p, Cursor& c) const {
  if (p < c.p) c = Cursor{};
  if (detached_) {  // the (i, j) of the totals against the pair's, both sorted
    const PairContact& q = pairs[p];
    const std::size_t nr = f_.size();
    while (c.r < nr && (ij_[c.r][0] < q.i || (ij_[c.r][0] == q.i && ij_[c.r][1] < q.j))) ++c.r;
    c.p = p;
    return c.r < nr && ij_[c.r][0] == q.i && ij_[c.r][1] == q.j ? &f_[c.r] : nullptr;
  }
  if (!allocated()) return nullptr;  // nothing recorded
  check_list(pairs);
  // The rank of p among the set bits: the bits of [c.p, p) counted, by words where they can be.
  while (c.p < p) {
    if ((c.p & 63) == 0 && c.p + 64 <= p) {
      c.r += static_cast<std::size_t>(__builtin_popcountll(bits_[c.p >> 6]));
      c.p += 64;
    } else {
      c.r += bit(c.p);
      ++c.p;
    }
  }
  return bit(p) ? &f_[c.r] : nullptr;
}

}  // namespace dem
