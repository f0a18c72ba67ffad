#include "physics/pair_normals.hpp"

#include <algorithm>
#include <utility>

namespace dem {

PairNormals::Record* PairNormals::start_pass() {
  // Room for the last pass's count and a margin: a pass rarely grows the buffer.
  const std::size_t want = n_ + n_ / 16 + 64;
  if (next_.size() < want) {
    std::vector<Record>().swap(next_);  // never the old and the new buffer at once
    next_.resize(want);
  }
  return next_.data();
}

PairNormals::Record* PairNormals::grow(Record* at) {
  const std::size_t k = static_cast<std::size_t>(at - next_.data());
  next_.resize(k + k / 8 + 64);
  return next_.data() + k;
}

void PairNormals::end_pass(const Record* at) {
  n_ = static_cast<std::size_t>(at - next_.data());
  now_.swap(next_);
}

void PairNormals::clear() {
  std::vector<Record>().swap(now_);
  std::vector<Record>().swap(next_);
  n_ = 0;
}

void PairNormals::compact(const RemovedDiscs& removed) {
  std::size_t o = 0;
  for (std::size_t k = 0; k < n_; ++k) {
    const Record q = now_[k];
    const int i = removed.new_index(q.i()), j = removed.new_index(q.j());
    if (i < 0 || j < 0) continue;
    now_[o++] = Record{key(i, j), q.fn};  // order kept: i, j only lose the removed discs below them
  }
  n_ = o;
}

void PairNormals::renumber(const std::vector<int>& new_index) {
  for (std::size_t k = 0; k < n_; ++k) {
    Record& q = now_[k];
    const int i = new_index[q.i()], j = new_index[q.j()];
    q.key = key(std::min(i, j), std::max(i, j));  // f_n is the same seen from either disc
  }
  std::sort(now_.begin(), now_.begin() + static_cast<std::ptrdiff_t>(n_),
            [](const Record& a, const Record& b) { return a.key < b.key; });
}

void PairNormals::assign(std::vector<Record> records) {
  n_ = records.size();
  now_ = std::move(records);
}

}  // namespace dem
