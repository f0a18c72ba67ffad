#include "state.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace dem {

namespace {
constexpr char kMagic[8] = {'D', 'E', 'M', 'S', 'T', 'A', 'T', '1'};

struct Writer {
  std::ofstream out;
  template <class T> void put(const T& v) { out.write(reinterpret_cast<const char*>(&v), sizeof v); }
  template <class T> void vec(const std::vector<T>& v) {
    put<std::uint64_t>(v.size());
    out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
  }
};

struct Reader {
  std::ifstream in;
  std::string path;
  void fail(const std::string& why) { throw std::runtime_error(path + ": " + why); }
  template <class T> T get() {
    T v;
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) fail("truncated state file");
    return v;
  }
  template <class T> void vec(std::vector<T>& v, std::uint64_t limit) {
    const auto n = get<std::uint64_t>();
    if (n > limit) fail("corrupt state file (array of " + std::to_string(n) + " entries)");
    v.resize(n);
    if (!in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T))))
      fail("truncated state file");
  }
};
}  // namespace

void save_state(const World& w, const std::string& path) {
  const std::string tmp = path + ".tmp";
  {
    Writer o{std::ofstream(tmp, std::ios::binary)};
    if (!o.out) throw std::runtime_error("cannot write " + tmp);
    o.out.write(kMagic, sizeof kMagic);
    o.put(w.time);
    o.put(w.steps);
    o.put(w.dt);
    o.put<std::int32_t>(static_cast<std::int32_t>(w.scheme));
    const Discs& d = w.discs;
    o.vec(d.r); o.vec(d.mass); o.vec(d.inv_mass); o.vec(d.inv_inertia); o.vec(d.material); o.vec(d.id);
    o.vec(d.x); o.vec(d.y); o.vec(d.phi); o.vec(d.vx); o.vec(d.vy); o.vec(d.omega);
    o.vec(d.dux); o.vec(d.duy); o.vec(d.dphi); o.vec(d.fx); o.vec(d.fy); o.vec(d.torque);
    std::vector<char> active;
    for (const Wall& wl : w.geometry.walls) active.push_back(wl.active ? 1 : 0);
    o.vec(active);
    o.vec(w.neighbors.pairs);
    o.vec(w.neighbors.walls);
    o.out.flush();
    if (!o.out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

void load_state(World& w, const std::string& path) {
  Reader r{std::ifstream(path, std::ios::binary), path};
  if (!r.in) r.fail("cannot open the state file");
  char magic[8];
  if (!r.in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0)
    r.fail("not a dem state file (or another format version)");
  w.time = r.get<double>();
  w.steps = r.get<long>();
  const double dt = r.get<double>();
  const auto scheme = r.get<std::int32_t>();
  if (dt != w.dt) r.fail("saved with dt = " + std::to_string(dt) + ", the scene has " + std::to_string(w.dt));
  if (scheme != static_cast<std::int32_t>(w.scheme)) r.fail("saved with another integration scheme");
  Discs& d = w.discs;
  const std::uint64_t lim = 1ull << 32;
  r.vec(d.r, lim); r.vec(d.mass, lim); r.vec(d.inv_mass, lim); r.vec(d.inv_inertia, lim);
  r.vec(d.material, lim); r.vec(d.id, lim);
  r.vec(d.x, lim); r.vec(d.y, lim); r.vec(d.phi, lim); r.vec(d.vx, lim); r.vec(d.vy, lim); r.vec(d.omega, lim);
  r.vec(d.dux, lim); r.vec(d.duy, lim); r.vec(d.dphi, lim); r.vec(d.fx, lim); r.vec(d.fy, lim); r.vec(d.torque, lim);
  const std::size_t n = d.r.size();
  for (auto* v : {&d.mass, &d.inv_mass, &d.inv_inertia, &d.x, &d.y, &d.phi, &d.vx, &d.vy, &d.omega, &d.dux, &d.duy,
                  &d.dphi, &d.fx, &d.fy, &d.torque})
    if (v->size() != n) r.fail("corrupt state file (arrays of different lengths)");
  if (d.material.size() != n || d.id.size() != n) r.fail("corrupt state file (arrays of different lengths)");
  for (int m : d.material)
    if (m < 0 || m >= w.n_materials) r.fail("a disc material does not exist in this scene");
  std::vector<char> active;
  r.vec(active, 1u << 20);
  if (active.size() != w.geometry.walls.size()) r.fail("saved with another set of walls");
  for (std::size_t k = 0; k < active.size(); ++k) w.geometry.walls[k].active = active[k] != 0;
  r.vec(w.neighbors.pairs, lim);
  r.vec(w.neighbors.walls, lim);
  for (const auto& p : w.neighbors.pairs)
    if (p.i < 0 || p.j < 0 || static_cast<std::size_t>(p.j) >= n || p.i >= p.j) r.fail("corrupt contact list");
  for (const auto& c : w.neighbors.walls)
    if (c.i < 0 || static_cast<std::size_t>(c.i) >= n || c.k < 0 || c.k >= w.geometry.obstacle_count())
      r.fail("corrupt wall-contact list");
  w.neighbors.invalidate();
  w.prepare();  // rebuild lists; the restored history is merged in
}

}  // namespace dem
