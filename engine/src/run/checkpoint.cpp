#include "run/checkpoint.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "io/files.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"

namespace dem {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'C', 'K', 'P', 'T', 'E'};  // the format's version: a checkpoint resumes only in its own
constexpr std::uint64_t kFnvOffset = 1469598103934665603ull, kFnvPrime = 1099511628211ull;

std::uint64_t fnv1a(const char* p, std::size_t n, std::uint64_t h = kFnvOffset) {
  for (std::size_t k = 0; k < n; ++k) {
    h ^= static_cast<unsigned char>(p[k]);
    h *= kFnvPrime;
  }
  return h;
}

// FNV-1a 64 of the next n bytes of `in` (fewer at its end: `got` says how many), in blocks.
std::uint64_t fnv1a_stream(std::istream& in, std::uint64_t n, std::uint64_t& got, std::uint64_t h = kFnvOffset) {
  char buf[1 << 16];
  got = 0;
  while (got < n) {
    in.read(buf, static_cast<std::streamsize>(std::min<std::uint64_t>(n - got, sizeof buf)));
    if (in.gcount() <= 0) break;
    h = fnv1a(buf, static_cast<std::size_t>(in.gcount()), h);
    got += static_cast<std::uint64_t>(in.gcount());
  }
  return h;
}

// Passes what is written on to `to` in blocks, hashing it (FNV-1a 64) on the way: the checksum
// that closes a checkpoint, without the checkpoint in memory (at a million discs, hundreds of MB).
class HashingBuf : public std::streambuf {
 public:
  explicit HashingBuf(std::streambuf* to) : to_(to) { setp(buf_, buf_ + sizeof buf_); }
  std::uint64_t finish() {  // the hash of everything written
    flush_block();
    return hash_;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!flush_block()) return traits_type::eof();
    if (c != traits_type::eof()) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return flush_block() ? 0 : -1; }

 private:
  bool flush_block() {
    const std::streamsize n = pptr() - pbase();
    hash_ = fnv1a(pbase(), static_cast<std::size_t>(n), hash_);
    const bool ok = to_->sputn(pbase(), n) == n;
    setp(buf_, buf_ + sizeof buf_);
    return ok;
  }
  std::streambuf* to_;
  std::uint64_t hash_ = kFnvOffset;
  char buf_[1 << 16];
};

std::string hex(std::uint64_t v) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

}  // namespace

std::uint64_t file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read the scene file");
  std::uint64_t got = 0;
  return fnv1a_stream(in, ~0ull, got);
}

CheckpointKey checkpoint_key(const std::string& scene_file, const SceneOverrides& ov) {
  CheckpointKey k;
  k.engine = std::string("dem ") + DEM_VERSION + " (" + DEM_BUILD_ID + ")";
  k.scene_hash = file_hash(scene_file);
  std::ostringstream os;
  os << "dt=" << (ov.dt > 0 ? fmt17(ov.dt) : "") << ";scheme=" << ov.scheme
     << ";end_time=" << (ov.end_time > 0 ? fmt17(ov.end_time) : "") << ";force_dt=" << (ov.force_dt ? 1 : 0)
     << ";from=" << ov.from << ";threads=" << ov.threads;
  for (const std::string& a : ov.sets) os << ";set=" << a;
  k.overrides = os.str();
  return k;
}

std::string checkpoint_path(const std::string& out_dir) { return out_dir + "/checkpoint.dem"; }

void write_checkpoint(const std::string& path, const CheckpointKey& key, const World& w, const Runner& runner,
                      const Rest& rest, const std::string& phase, const Phase* state) {
  write_stream_atomic(path, [&](std::ostream& file) {
    // Streamed into the file through the hash: no copy of the checkpoint in memory.
    HashingBuf hashing(file.rdbuf());
    std::ostream buf(&hashing);
    BinaryOut o{buf};
    buf.write(kMagic, sizeof kMagic);
    o.str(key.engine);
    o.put(key.scene_hash);
    o.str(key.overrides);
    o.str(phase);
    // The runner (runner.hpp): clock, guard, last good state.
    o.put(runner.wall_now());
    o.put(runner.guard.overlap_limit);
    const EnergyWatch& e = runner.guard.energy;
    o.put(e.active); o.put(e.budget); o.put(e.scale); o.put(e.gain);
    runner.last_good.write_to(o);
    // The fill's rest measure (fill_phase.hpp).
    o.put(rest.reached); o.put(rest.time); o.put(rest.threshold); o.put(rest.mean_abs_du); o.put(rest.mean_abs_dv);
    runner.record.save(o);  // thermo.csv and snapshots.pvd so far (recorder.hpp)
    // The world, its counters and its lists exactly as they are (no rebuild on resume).
    write_world(o, w);
    o.put(w.particle_steps);
    o.put(w.neighbors.rebuilds);
    o.put(w.neighbors.patches);
    o.put(w.resorts);
    const Neighbors::Reference ref = w.neighbors.reference();
    o.put(ref.cell); o.put(ref.ox); o.put(ref.oy); o.put(ref.limit2);
    o.vec(w.neighbors.reference_x());
    o.vec(w.neighbors.reference_y());
    if (state) state->save(o);
    buf.flush();
    if (!buf) throw std::runtime_error("cannot write " + path + ".tmp");
    const std::uint64_t sum = hashing.finish();
    file.write(reinterpret_cast<const char*>(&sum), sizeof sum);
  });
}

void read_checkpoint(const std::string& path, const CheckpointKey& key, World& w, Runner& runner, Rest& rest,
                     std::string& phase, const std::function<void(const std::string&, BinaryIn&)>& load_phase) {
  // Two passes over the file, neither holding it in memory: the checksum over every byte before
  // the last 8 (which hold it), then the reading.
  std::uint64_t size = 0;
  {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error(path + ": cannot open the checkpoint");
    std::error_code ec;
    size = std::filesystem::file_size(path, ec);
    char magic[sizeof kMagic];
    std::uint64_t sum = 0;
    if (ec || size < sizeof kMagic + sizeof sum || !f.read(magic, sizeof magic) ||
        std::memcmp(magic, kMagic, sizeof kMagic) != 0)
      throw std::runtime_error(path + ": not a dem checkpoint (or another format version)");
    const std::uint64_t body = size - sizeof kMagic - sizeof sum;
    std::uint64_t got = 0;
    const std::uint64_t h = fnv1a_stream(f, body, got, fnv1a(magic, sizeof magic));
    if (got != body) throw std::runtime_error(path + ": damaged checkpoint (cut short)");
    if (!f.read(reinterpret_cast<char*>(&sum), sizeof sum) || h != sum)
      throw std::runtime_error(path + ": damaged checkpoint (checksum)");
  }
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(sizeof kMagic));
  BinaryIn r{in, path};
  const std::string engine = r.str(256);
  if (engine != key.engine)
    r.fail("written by " + engine + ", this is " + key.engine + ": a checkpoint resumes only with the same engine");
  const auto scene_hash = r.get<std::uint64_t>();
  if (scene_hash != key.scene_hash)
    r.fail("written for a scene file with hash " + hex(scene_hash) + ", the scene file now has " + hex(key.scene_hash) +
           ": the scene changed since the checkpoint (run it afresh without --resume)");
  const std::string overrides = r.str(1 << 16);
  if (overrides != key.overrides)
    r.fail("written with the options \"" + overrides + "\", now \"" + key.overrides +
           "\": --dt, --scheme, --end-time, --force-dt and --from must be as in the checkpointed run");
  phase = r.str(64);
  runner.wall_seconds = r.get<double>();
  runner.guard.overlap_limit = r.get<double>();
  EnergyWatch& e = runner.guard.energy;
  e.active = r.get<bool>(); e.budget = r.get<double>(); e.scale = r.get<double>(); e.gain = r.get<double>();
  runner.last_good.read_from(r);
  rest.reached = r.get<bool>(); rest.time = r.get<double>(); rest.threshold = r.get<double>();
  rest.mean_abs_du = r.get<double>(); rest.mean_abs_dv = r.get<double>();
  runner.record.load(r);
  read_world(r, w);
  w.particle_steps = r.get<double>();
  const long rebuilds = r.get<long>();
  const long patches = r.get<long>();
  const long resorts = r.get<long>();
  Neighbors::Reference ref{};
  ref.cell = r.get<double>();
  ref.ox = r.get<double>();
  ref.oy = r.get<double>();
  ref.limit2 = r.get<double>();
  std::vector<float> x0, y0;
  r.vec(x0);
  r.vec(y0);
  if (x0.size() != y0.size() || (!x0.empty() && x0.size() != w.discs.size()))
    r.fail("corrupt checkpoint (reference positions)");
  load_phase(phase, r);  // the phase's own state (the fill's is its rest measure, read above)
  if (static_cast<std::uint64_t>(in.tellg()) != size - sizeof(std::uint64_t)) r.fail("corrupt checkpoint (trailing bytes)");
  // Kernel, point links and scratch as for any start, with the lists exactly as saved (no build
  // beside them: the pair list is the largest array).
  w.prepare(false);
  w.neighbors.rebuilds = rebuilds;
  w.neighbors.patches = patches;
  w.resorts = resorts;
  w.neighbors.restore_reference(std::move(x0), std::move(y0), ref);
}

}  // namespace dem
