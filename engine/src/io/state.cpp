#include "io/state.hpp"

#include <cstddef>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "io/files.hpp"

namespace dem {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'S', 'T', 'A', 'T', '7'};  // the format's version
// Version 6 lacks the onset scheme's kept f_n (World::onset_normals), written last: read without
// them (the first step after it makes no slip correction on a disc pair).
constexpr char kVersion6 = '6';

// The wall contacts in their memory layout with the padding after `touching` zeroed, so that
// equal states give equal files.
std::vector<WallContact> zero_padded(const std::vector<WallContact>& v) {
  std::vector<WallContact> out(v.size());
  if (out.empty()) return out;  // no data() to clear (memset of a null pointer is undefined)
  std::memset(static_cast<void*>(out.data()), 0, out.size() * sizeof(WallContact));
  for (std::size_t k = 0; k < v.size(); ++k) {
    char* to = reinterpret_cast<char*>(&out[k]);
    const WallContact& c = v[k];
    std::memcpy(to + offsetof(WallContact, i), &c.i, sizeof c.i);
    std::memcpy(to + offsetof(WallContact, k), &c.k, sizeof c.k);
    std::memcpy(to + offsetof(WallContact, en), &c.en, offsetof(WallContact, touching) - offsetof(WallContact, en));
    std::memcpy(to + offsetof(WallContact, touching), &c.touching, sizeof c.touching);
  }
  return out;
}

// Paper 2's bonds and moving walls, field by field (their structs have padding). What the scene
// builds (which discs are bonded, lever arms, pivots, the plate's place and mass) is written
// too, and must match on reading: a state fits only the box and clusters it was saved from.
void write_paper2(BinaryOut& o, const World& w) {
  o.put<std::uint64_t>(w.bonds.size());
  for (const Bond& b : w.bonds) {
    o.put(b.i); o.put(b.j); o.put(b.ai); o.put(b.aj); o.put(b.rest);
    o.put(b.en); o.put(b.es); o.put(b.fn); o.put(b.fs);
  }
  const MovingWalls& m = w.moving;
  o.put<std::uint64_t>(m.rotating.size());
  for (const RotatingWall& r : m.rotating) {
    o.put(r.wall); o.put(r.pivot_x); o.put(r.pivot_y); o.put(r.ax0); o.put(r.ay0); o.put(r.bx0); o.put(r.by0);
    o.put(r.theta); o.put(r.omega); o.put(r.theta_listed);
  }
  o.put<std::uint64_t>(m.plates.size());
  for (const RigidPlate& p : m.plates) {
    o.put(p.wall); o.put(p.mass); o.put(p.ax0); o.put(p.ay0); o.put(p.bx0); o.put(p.by0); o.put(p.follow);
    o.put(p.x_free); o.put(p.x); o.put(p.y); o.put(p.vx); o.put(p.vy); o.put(p.dux); o.put(p.duy);
    o.put(p.x_listed); o.put(p.y_listed);
  }
  // Prescribed translations: their place follows the clock; the place at the last list build does not.
  o.put<std::uint64_t>(m.translating.size());
  for (const TranslatingWall& q : m.translating) {
    o.put(q.wall); o.put(q.vx); o.put(q.vy); o.put(q.t_from); o.put(q.t_until);
    o.put(q.x_listed); o.put(q.y_listed);
  }
  o.vec(m.motion);  // the last increments (contact law 5a, 5b) and forces (the plate's next kick)
}

void read_paper2(BinaryIn& r, World& w) {
  const auto fits = [&](bool ok, const char* what) {
    if (!ok) r.fail(std::string("saved with ") + what + " than the scene builds");
  };
  const std::uint64_t nb = r.count(1ull << 32);
  fits(nb == w.bonds.size(), "another number of cluster bonds");
  for (Bond& b : w.bonds) {
    const int i = r.get<int>(), j = r.get<int>();
    const double ai = r.get<double>(), aj = r.get<double>(), rest = r.get<double>();
    fits(i == b.i && j == b.j && ai == b.ai && aj == b.aj && rest == b.rest, "other cluster bonds");
    if (static_cast<std::size_t>(j) >= w.discs.size()) r.fail("fewer discs than the scene's clusters bind");
    b.en = r.get<double>(); b.es = r.get<double>(); b.fn = r.get<double>(); b.fs = r.get<double>();
  }
  MovingWalls& m = w.moving;
  fits(r.count(1u << 20) == m.rotating.size(), "another number of turning walls");
  for (RotatingWall& q : m.rotating) {
    const int wall = r.get<int>();
    double fixed[6];
    for (double& v : fixed) v = r.get<double>();
    fits(wall == q.wall && fixed[0] == q.pivot_x && fixed[1] == q.pivot_y && fixed[2] == q.ax0 &&
             fixed[3] == q.ay0 && fixed[4] == q.bx0 && fixed[5] == q.by0,
         "other turning walls");
    q.theta = r.get<double>(); q.omega = r.get<double>(); q.theta_listed = r.get<double>();
  }
  fits(r.count(1u << 20) == m.plates.size(), "another number of plates");
  for (RigidPlate& p : m.plates) {
    const int wall = r.get<int>();
    double fixed[5];
    for (double& v : fixed) v = r.get<double>();
    const int follow = r.get<int>();
    fits(wall == p.wall && fixed[0] == p.mass && fixed[1] == p.ax0 && fixed[2] == p.ay0 && fixed[3] == p.bx0 &&
             fixed[4] == p.by0,
         "another plate (its place or mass)");
    fits(follow == p.follow, "the plate moving otherwise (shear_box.plate_horizontal)");
    p.x_free = r.get<double>(); p.x = r.get<double>(); p.y = r.get<double>();
    p.vx = r.get<double>(); p.vy = r.get<double>(); p.dux = r.get<double>(); p.duy = r.get<double>();
    p.x_listed = r.get<double>(); p.y_listed = r.get<double>();
  }
  fits(r.count(1u << 20) == m.translating.size(), "another number of translating walls");
  for (TranslatingWall& q : m.translating) {
    const int wall = r.get<int>();
    double fixed[4];
    for (double& v : fixed) v = r.get<double>();
    fits(wall == q.wall && fixed[0] == q.vx && fixed[1] == q.vy && fixed[2] == q.t_from && fixed[3] == q.t_until,
         "another wall translation (walls[].velocity, move_from, move_until)");
    q.x_listed = r.get<double>(); q.y_listed = r.get<double>();
  }
  std::vector<ObstacleMotion> motion;
  r.vec(motion, 1u << 20);
  fits(motion.size() == m.motion.size(), "another set of moving obstacles");
  m.motion = std::move(motion);
  for (const RotatingWall& q : m.rotating)
    if (!std::isfinite(q.theta)) r.fail("corrupt file (a wall's angle not finite)");
  for (const RigidPlate& p : m.plates)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) r.fail("corrupt file (the plate's place not finite)");
  w.place_moving_walls();
}
}  // namespace

void write_discs(BinaryOut& o, const Discs& d) {
  const DiscKinds& k = d.kinds;
  o.vec(k.r); o.vec(k.mass); o.vec(k.inv_mass); o.vec(k.inv_inertia); o.vec(k.material);
  // An array a scene leaves out (one kind: zeros; no removal: the indices) is written as the
  // array it stands for, in blocks (the same format, no array of all discs in memory).
  const auto implicit = [&](auto value_at) {
    std::vector<int> block(std::min<std::size_t>(d.size(), 4096));
    o.put<std::uint64_t>(d.size());
    for (std::size_t done = 0; done < d.size(); done += block.size()) {
      const std::size_t m = std::min(block.size(), d.size() - done);
      for (std::size_t k = 0; k < m; ++k) block[k] = value_at(done + k);
      o.out.write(reinterpret_cast<const char*>(block.data()), static_cast<std::streamsize>(m * sizeof(int)));
    }
  };
  if (d.kind.empty()) implicit([](std::size_t) { return 0; });
  else o.vec(d.kind);
  if (d.id.empty()) implicit([](std::size_t i) { return static_cast<int>(i); });
  else o.vec(d.id);
  o.vec(d.x); o.vec(d.y); o.vec(d.phi); o.vec(d.vx); o.vec(d.vy); o.vec(d.omega);
  o.vec(d.dux); o.vec(d.duy); o.vec(d.dphi); o.vec(d.fx); o.vec(d.fy); o.vec(d.torque);
}

void read_discs(BinaryIn& r, Discs& d) {
  DiscKinds& k = d.kinds;
  r.vec(k.r); r.vec(k.mass); r.vec(k.inv_mass); r.vec(k.inv_inertia); r.vec(k.material);
  for (std::size_t n : {k.mass.size(), k.inv_mass.size(), k.inv_inertia.size(), k.material.size()})
    if (n != k.size()) r.fail("corrupt file (kind arrays of different lengths)");
  r.vec(d.kind); r.vec(d.id);
  r.vec(d.x); r.vec(d.y); r.vec(d.phi); r.vec(d.vx); r.vec(d.vy); r.vec(d.omega);
  r.vec(d.dux); r.vec(d.duy); r.vec(d.dphi); r.vec(d.fx); r.vec(d.fy); r.vec(d.torque);
  const std::size_t n = d.kind.size();
  for (int c : d.kind)
    if (c < 0 || static_cast<std::size_t>(c) >= k.size()) r.fail("corrupt file (a disc of no kind)");
  for (auto* v : {&d.x, &d.y, &d.vx, &d.vy, &d.omega, &d.fx, &d.fy,
                  &d.torque})
    if (v->size() != n) r.fail("corrupt file (arrays of different lengths)");
  for (auto* v : {&d.dux, &d.duy, &d.dphi, &d.phi})  // kept by eq. 19 / with the rotation angle only
    if (v->size() != n && !v->empty()) r.fail("corrupt file (arrays of different lengths)");
  if (d.id.size() != n) r.fail("corrupt file (arrays of different lengths)");
  d.drop_derivable_arrays();
  d.count_ids();  // the next id after the largest (the discs may be in cell order)
}

void write_world(BinaryOut& o, const World& w) {
  w.require_velocities("write_world");
  o.put(w.time);
  o.put(w.steps);
  o.put(w.dt);
  o.put<std::int32_t>(static_cast<std::int32_t>(w.scheme));
  write_discs(o, w.discs);
  std::vector<char> active;
  for (const Wall& wl : w.geometry.walls) active.push_back(wl.active ? 1 : 0);
  o.vec(active);
  o.vec(w.neighbors.pairs);
  o.vec(zero_padded(w.neighbors.walls));
  o.put(w.pair_forces_step);  // the recorded totals (outputs), so a state saved at its end writes them again
  // As (i, j, fn, fs) records, whatever their form in memory: written one by one, not copied.
  o.put<std::uint64_t>(w.pair_totals.size());
  w.each_recorded_pair([&](int i, int j, double fn, double fs) { o.put(PairForce{i, j, fn, fs}); });
  o.vec(w.force_blocks);
  write_paper2(o, w);
  // velocity_verlet_onset, friction_cap total: each touching pair's f_n (as o.vec, without a copy)
  const PairNormals& fn = w.onset_normals;
  o.put<std::uint64_t>(fn.size());
  o.out.write(reinterpret_cast<const char*>(fn.begin()), static_cast<std::streamsize>(fn.size() * sizeof(PairNormals::Record)));
}

void read_world(BinaryIn& r, World& w, bool onset_normals) {
  w.time = r.get<double>();
  w.steps = r.get<long>();
  const double dt = r.get<double>();
  const auto scheme = r.get<std::int32_t>();
  if (dt != w.dt) r.fail("saved with dt = " + fmt17(dt) + ", the scene has " + fmt17(w.dt));
  if (scheme != static_cast<std::int32_t>(w.scheme)) r.fail("saved with another integration scheme");
  Discs& d = w.discs;
  read_discs(r, d);
  const std::size_t n = d.size();
  for (int m : d.kinds.material)
    if (m < 0 || m >= w.n_materials) r.fail("a disc material does not exist in this scene");
  std::vector<char> active;
  r.vec(active, 1u << 20);
  if (active.size() != w.geometry.walls.size()) r.fail("saved with another set of walls");
  for (std::size_t k = 0; k < active.size(); ++k) w.geometry.walls[k].active = active[k] != 0;
  r.vec(w.neighbors.pairs);
  r.vec(w.neighbors.walls);
  for (const auto& p : w.neighbors.pairs)
    if (p.i < 0 || p.j < 0 || static_cast<std::size_t>(p.j) >= n || p.i >= p.j) r.fail("corrupt contact list");
  for (const auto& c : w.neighbors.walls)
    if (c.i < 0 || static_cast<std::size_t>(c.i) >= n || c.k < 0 || c.k >= w.geometry.obstacle_count())
      r.fail("corrupt wall-contact list");
  w.pair_forces_step = r.get<long>();
  // Detached (with their (i, j)): the lists may be built again before the totals are read.
  const std::uint64_t nrec = r.count(1ull << 32);
  w.pair_totals.start_detached(nrec);
  for (std::uint64_t k = 0; k < nrec; ++k) {
    const auto p = r.get<PairForce>();
    if (p.i < 0 || p.j < 0 || static_cast<std::size_t>(p.j) >= n || p.i >= p.j) r.fail("corrupt pair-force record");
    w.pair_totals.push(p);
  }
  r.vec(w.force_blocks);
  for (std::size_t t = 0; t < w.force_blocks.size(); ++t)
    if ((t == 0 && w.force_blocks[t] != 0) || (t > 0 && w.force_blocks[t] < w.force_blocks[t - 1]) ||
        (t + 1 == w.force_blocks.size() && static_cast<std::size_t>(w.force_blocks[t]) != n))
      r.fail("corrupt thread blocks");
  read_paper2(r, w);
  std::vector<PairNormals::Record> fn;
  if (onset_normals) r.vec(fn);
  for (std::size_t k = 0; k < fn.size(); ++k) {
    const PairNormals::Record& q = fn[k];
    if (q.i() < 0 || q.i() >= q.j() || static_cast<std::size_t>(q.j()) >= n || (k > 0 && fn[k - 1].key >= q.key))
      r.fail("corrupt pair normal-force record");
  }
  w.onset_normals.assign(std::move(fn));
}

void save_state(const World& w, const std::string& path) {
  std::ostringstream buf(std::ios::binary);
  BinaryOut o{buf};
  buf.write(kMagic, sizeof kMagic);
  write_world(o, w);
  write_file_atomic(path, buf.str());
}

void load_state(World& w, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  BinaryIn r{in, path};
  if (!in) r.fail("cannot open the state file");
  char magic[8];
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic - 1) != 0 ||
      (magic[7] != kMagic[7] && magic[7] != kVersion6))
    r.fail("not a dem state file (or another format version)");
  read_world(r, w, magic[7] != kVersion6);
  w.neighbors.invalidate();
  w.prepare();  // rebuild lists; the restored history is merged in
}

}  // namespace dem
