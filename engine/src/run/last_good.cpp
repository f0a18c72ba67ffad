#include "run/last_good.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/files.hpp"
#include "io/state.hpp"

namespace dem {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'G', 'O', 'O', 'D', '1'};

// The file: magic, time [s], then state.hpp's write_discs (each array as a uint64 count and its
// values, this machine's byte order).
void write_kept(std::ostream& out, const Discs& d, double t) {
  BinaryOut o{out};
  out.write(kMagic, sizeof kMagic);
  o.put(t);
  write_discs(o, d);
}

Discs read_kept(std::istream& in, const std::string& name) {
  BinaryIn r{in, name};
  char magic[sizeof kMagic];
  if (!in.read(magic, sizeof magic) || !std::equal(magic, magic + sizeof magic, kMagic))
    r.fail("not a last good state of this engine");
  r.get<double>();
  Discs d;
  read_discs(r, d);
  return d;
}
}  // namespace

void LastGood::keep(const Discs& d, double t) {
  if (path_.empty()) {
    std::ostringstream buf(std::ios::binary);
    write_kept(buf, d, t);
    bytes_ = std::move(buf).str();
  } else {
    write_stream_atomic(path_, [&](std::ostream& out) { write_kept(out, d, t); });
  }
  has_ = true;
  time_ = t;
}

Discs LastGood::load() const {
  if (!has_) throw std::logic_error("LastGood::load: nothing kept");
  if (path_.empty()) {
    std::istringstream in(bytes_, std::ios::binary);
    return read_kept(in, "last good state (memory)");
  }
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw std::runtime_error(path_ + ": the last good state cannot be read back (file gone?)");
  return read_kept(in, path_);
}

void LastGood::write_to(BinaryOut& o) const {
  o.put(has_);
  o.put(time_);
  if (!has_) return;
  if (path_.empty()) {
    o.str(bytes_);
    return;
  }
  // Streamed from the file: the checkpoint does not hold a second copy of it in memory.
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw std::runtime_error(path_ + ": the last good state cannot be read back (file gone?)");
  o.put<std::uint64_t>(std::filesystem::file_size(path_));
  o.out << in.rdbuf();
}

void LastGood::read_from(BinaryIn& r) {
  has_ = r.get<bool>();
  time_ = r.get<double>();
  bytes_.clear();
  if (!has_) return;
  const std::uint64_t n = r.count(1ull << 40);
  if (path_.empty()) {
    std::ostringstream buf(std::ios::binary);
    r.copy_to(buf, n);
    bytes_ = std::move(buf).str();
  } else {
    write_stream_atomic(path_, [&](std::ostream& out) { r.copy_to(out, n); });
  }
}

void LastGood::discard() {
  has_ = false;
  bytes_.clear();
  bytes_.shrink_to_fit();
  if (!path_.empty()) {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
}

}  // namespace dem
