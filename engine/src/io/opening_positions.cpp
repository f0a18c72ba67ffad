#include "io/opening_positions.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>

#include "io/files.hpp"
#include "io/state.hpp"

namespace dem {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'O', 'P', 'E', 'N', '1'};

// The file (opening_positions.hpp): its header, then what `positions` writes (x, y per id).
void write_positions_file(const std::string& path, std::uint64_t count, const std::function<void(std::ostream&)>& positions) {
  write_stream_atomic(path, [&](std::ostream& out) {
    out.write(kMagic, sizeof kMagic);
    BinaryOut{out}.put(count);
    positions(out);
  });
}
}  // namespace

void OpeningPositions::keep(const Discs& d) {
  int max_id = -1;
  for (std::size_t i = 0; i < d.size(); ++i) max_id = std::max(max_id, d.id_at(i));
  count_ = static_cast<std::uint64_t>(max_id + 1);
  // Written in increasing id order, in blocks, gaps as NaN, without an array of all ids in memory.
  // Discs in cell order (World::resort_discs) are read through their id order.
  const std::vector<int> by_id = d.by_id();
  const auto disc = [&](std::size_t k) { return by_id.empty() ? k : static_cast<std::size_t>(by_id[k]); };
  std::vector<double> block;
  std::size_t i = 0;
  auto fill = [&](std::uint64_t first, std::uint64_t n) {
    block.assign(2 * n, NAN);
    for (; i < d.size() && static_cast<std::uint64_t>(d.id_at(disc(i))) < first + n; ++i) {
      const std::uint64_t k = static_cast<std::uint64_t>(d.id_at(disc(i))) - first;
      block[2 * k] = d.x[disc(i)];
      block[2 * k + 1] = d.y[disc(i)];
    }
  };
  for (std::size_t k = 1; k < d.size(); ++k)
    if (d.id_at(disc(k)) <= d.id_at(disc(k - 1))) throw std::logic_error("OpeningPositions::keep: ids not distinct");
  if (path_.empty()) {
    fill(0, count_);
    xy_ = std::move(block);
    return;
  }
  xy_.clear();
  write_positions_file(path_, count_, [&](std::ostream& out) {
    for (std::uint64_t first = 0; first < count_; first += kBlock) {
      fill(first, std::min(kBlock, count_ - first));
      out.write(reinterpret_cast<const char*>(block.data()), static_cast<std::streamsize>(block.size() * sizeof(double)));
    }
  });
}

void OpeningPositions::Reader::at(int id, double& x0, double& y0) {
  const auto k = static_cast<std::uint64_t>(id);
  if (id < 0 || k >= p_.count_) throw std::out_of_range("OpeningPositions: no disc id " + std::to_string(id));
  if (p_.path_.empty()) {
    x0 = p_.xy_[2 * k];
    y0 = p_.xy_[2 * k + 1];
    return;
  }
  if (block_.empty() || k < first_ || k >= first_ + block_.size() / 2) {
    first_ = k / kBlock * kBlock;
    const std::uint64_t n = std::min(kBlock, p_.count_ - first_);
    block_.resize(2 * n);
    std::ifstream in(p_.path_, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(kHeader + 2 * sizeof(double) * first_));
    if (!in.read(reinterpret_cast<char*>(block_.data()), static_cast<std::streamsize>(block_.size() * sizeof(double)))) {
      block_.clear();
      throw std::runtime_error(p_.path_ + ": the positions at opening cannot be read back (file gone or cut short?)");
    }
  }
  x0 = block_[2 * (k - first_)];
  y0 = block_[2 * (k - first_) + 1];
}

void OpeningPositions::write_to(BinaryOut& o) const {
  o.put(count_);
  if (path_.empty()) {
    o.out.write(reinterpret_cast<const char*>(xy_.data()), static_cast<std::streamsize>(xy_.size() * sizeof(double)));
    return;
  }
  if (count_ == 0) return;
  std::ifstream in(path_, std::ios::binary);  // streamed: no second copy in memory
  in.seekg(static_cast<std::streamoff>(kHeader));
  if (!in) throw std::runtime_error(path_ + ": the positions at opening cannot be read back (file gone?)");
  o.out << in.rdbuf();
}

void OpeningPositions::read_from(BinaryIn& r) {
  count_ = r.count(1ull << 34);
  const std::uint64_t bytes = 2 * sizeof(double) * count_;
  if (path_.empty()) {
    xy_.resize(2 * count_);
    if (!r.in.read(reinterpret_cast<char*>(xy_.data()), static_cast<std::streamsize>(bytes))) r.fail("truncated file");
    return;
  }
  xy_.clear();
  write_positions_file(path_, count_, [&](std::ostream& out) { r.copy_to(out, bytes); });
}

void OpeningPositions::discard() {
  count_ = 0;
  std::vector<double>().swap(xy_);
  if (!path_.empty()) {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
}

}  // namespace dem
