#include "physics/pair_normals.hpp"

#include <algorithm>
#include <utility>

namespace dem {

void PairNormals::clear() {
  std::vector<Record>().swap(now_);
  std::vector<Record>().swap(next_);
}

void PairNormals::compact(const RemovedDiscs& removed) {
  std::size_t o = 0;
  for (const Record& q : now_) {
    const int i = removed.new_index(q.i), j = removed.new_index(q.j);
    if (i < 0 || j < 0) continue;
    now_[o++] = Record{i, j, q.fn};
  }
  now_.resize(o);
}

void PairNormals::renumber(const std::vector<int>& new_index) {
  for (Record& q : now_) {
    const int i = new_index[q.i], j = new_index[q.j];
    q.i = std::min(i, j);  // f_n is the same seen from either disc
    q.j = std::max(i, j);
  }
  std::sort(now_.begin(), now_.end(), [](const Record& a, const Record& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
}

void PairNormals::assign(std::vector<Record> records) {
  now_ = std::move(records);
  next_.clear();
}

}  // namespace dem
