#include "scene/shear_scene.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "physics/world.hpp"
#include "scene/toml_reader.hpp"

namespace dem {

namespace {

// A material named by key (default `def` when absent, required when def < 0).
int material(Tab& t, const SceneSpec& s, const std::string& key, int def) {
  const toml::node* n = t.node(key);
  if (!n) {
    if (def >= 0) return def;
    t.fail(key, "", "required value is missing");
  }
  auto v = n->as_string();
  if (!v) t.fail(key, show(*n), "expected a material name");
  for (std::size_t m = 0; m < s.material_names.size(); ++m)
    if (s.material_names[m] == v->get()) return static_cast<int>(m);
  t.fail(key, '"' + v->get() + '"', "no such material in [materials]");
}

const toml::table* table(const toml::table& root, const std::string& key, const std::string& file) {
  const toml::node* n = root.get(key);
  if (!n) return nullptr;
  if (auto t = n->as_table()) return t;
  throw SceneError(file + ": " + key + ": expected a table [" + key + "]");
}

}  // namespace

void read_shear_tables(SceneSpec& s, const toml::table& root) {
  ShearBoxSpec& b = s.shear_box;
  if (const toml::table* tt = table(root, "shear_box", s.file)) {
    Tab t(*tt, "shear_box", s.file);
    b.enabled = true;
    b.width = t.bounded("width", default_length(s.units, b.width), true);
    b.height = t.bounded("height", default_length(s.units, b.height), true);
    b.wall_length = t.bounded("wall_length", 1.5 * b.height, true);
    if (b.wall_length < b.height) t.fail("wall_length", show(b.wall_length), "must be >= height = " + show(b.height));
    b.wall_material = material(t, s, "wall_material", -1);
    b.plate_material = material(t, s, "plate_material", b.wall_material);
    b.plate_volume = t.bounded("plate_volume", default_area(s.units, b.plate_volume), false, true);
    b.plate_density = t.bounded("plate_density", 0.0, false, true);
    b.plate_gap = t.bounded("plate_gap", default_length(s.units, b.plate_gap), false, true);
    b.plate_overhang = t.bounded("plate_overhang", default_length(s.units, b.plate_overhang), false, true);
    b.plate_follows_walls = t.choice("plate_horizontal", {"free", "with_walls"}, "free") == "with_walls";
    t.finish();
    const double W = b.width, L = b.wall_length;
    auto& walls = s.geometry.walls;
    // Side walls run top -> bottom (as the silo's), the floor and the plate left -> right.
    walls.push_back({"left", "side_left", 0, L, 0, 0, b.wall_material});
    walls.push_back({"right", "side_right", W, L, W, 0, b.wall_material});
    walls.push_back({"floor", "bottom", 0, 0, W, 0, b.wall_material});
  }
  if (const toml::table* tt = table(root, "shear", s.file)) {
    Tab t(*tt, "shear", s.file);
    if (!b.enabled) t.fail("rate", "", "[shear] needs a [shear_box]");
    b.shear = true;
    b.rate = t.bounded("rate", b.rate, true);
    b.max_strain = t.bounded("max_strain", b.max_strain, true);
    if (b.max_strain > 1) t.fail("max_strain", show(b.max_strain), "must be <= 1 (45 degrees)");
    b.sample_strain = t.bounded("sample_strain", b.sample_strain, true);
    if (b.max_strain / b.sample_strain > 1e6) t.fail("sample_strain", show(b.sample_strain), "gives more than 1e6 samples");
    b.snapshots = t.numbers("snapshots", b.snapshots);
    t.finish();
  }
  if (const toml::table* tt = table(root, "clusters", s.file)) {
    Tab t(*tt, "clusters", s.file);
    ClusterSpec& c = s.clusters;
    c.enabled = true;
    c.bonds = t.choice("bonds", {"all", "touching"}, "all") == "all" ? BondSet::all : BondSet::touching;
    c.touch_tolerance = t.bounded("touch_tolerance", default_length(s.units, c.touch_tolerance), false, true);
    const toml::node* n = t.node("members");
    if (!n) t.fail("members", "", "required value is missing");
    auto a = n->as_array();
    if (!a) t.fail("members", show(*n), "expected an array of disc-index arrays [[0, 1, 2], ...]");
    for (std::size_t k = 0; k < a->size(); ++k) {
      auto e = a->get(k)->as_array();
      const std::string f = "members[" + std::to_string(k) + "]";
      if (!e) t.fail(f, show(*a->get(k)), "expected an array of disc indices");
      if (e->size() < 2 || e->size() > 1000) t.fail(f, show(*e), "a cluster has 2 to 1000 discs");
      std::vector<int> m;
      for (const auto& x : *e) {
        auto i = x.as_integer();
        if (!i) t.fail(f, show(*e), "expected integer disc indices (0-based, fill order)");
        if (i->get() < 0 || i->get() > 2'000'000'000L) t.fail(f, show(*e), "disc indices must be >= 0");
        m.push_back(static_cast<int>(i->get()));
      }
      c.members.push_back(m);
    }
    t.finish();
  }
}

void finish_shear_tables(SceneSpec& s) {
  if (s.clusters.enabled) {
    const std::size_t n = s.discs.size();
    std::vector<int> owner(n, -1);
    for (std::size_t c = 0; c < s.clusters.members.size(); ++c) {
      const std::string f = s.file + ": clusters.members[" + std::to_string(c) + "]";
      for (int i : s.clusters.members[c]) {
        if (static_cast<std::size_t>(i) >= n)
          throw SceneError(f + ": disc index " + std::to_string(i) + " is out of range (the fill has " +
                           std::to_string(n) + " discs, indices 0 to " + std::to_string(n - 1) + ")");
        if (owner[i] == static_cast<int>(c))
          throw SceneError(f + ": disc " + std::to_string(i) + " is listed twice");
        if (owner[i] >= 0)
          throw SceneError(f + ": disc " + std::to_string(i) + " is already in clusters.members[" +
                           std::to_string(owner[i]) + "]");
        owner[i] = static_cast<int>(c);
      }
    }
  }
  ShearBoxSpec& b = s.shear_box;
  if (!b.enabled) return;
  if (b.shear) {  // step counts are integers; a wall must not turn far in one step
    const double steps = std::atan(b.max_strain) / (b.rate * s.dt);
    if (!(steps <= 1e12))
      throw SceneError(s.file + ": shear.rate = " + show(b.rate) + ": the shear takes " + show(steps) +
                       " steps of dt, more than the limit of 1e12 (docs/scene.md, Limits)");
    if (!(b.rate * s.dt <= 1e-3))
      throw SceneError(s.file + ": shear.rate = " + show(b.rate) + ": turns the walls by " + show(b.rate * s.dt) +
                       " rad per step of dt = " + show(s.dt) + " s, more than 1e-3");
  }
  double top = -1e300, rho = 0;
  for (const DiscInit& d : s.discs) {
    top = std::max(top, d.y + d.r);
    rho = std::max(rho, s.density[d.material]);
  }
  if (b.plate_density <= 0) b.plate_density = rho;
  b.plate_y = top + b.plate_gap;
  if (b.plate_y > b.wall_length)
    throw SceneError(s.file + ": shear_box.wall_length = " + show(b.wall_length) + ": the discs reach " + show(top) +
                     " " + unit_names(s.units).length + ", the plate must start below the walls' top");
  b.plate_mass = b.plate_volume * b.plate_density;
  if (!(b.plate_mass > 0))
    throw SceneError(s.file + ": shear_box.plate_volume = " + show(b.plate_volume) + ": the plate needs a mass > 0");
  s.geometry.walls.push_back({"plate", "plate", -b.plate_overhang, b.plate_y, b.width + b.plate_overhang, b.plate_y,
                              b.plate_material});
}

namespace {

int wall_index(const World& w, const std::string& name) {
  for (std::size_t k = 0; k < w.geometry.walls.size(); ++k)
    if (w.geometry.walls[k].name == name) return static_cast<int>(k);
  throw SceneError("shear box: no wall named \"" + name + "\"");
}

}  // namespace

void build_shear_world(const SceneSpec& s, World& w) {
  if (s.clusters.enabled) {
    try {
      w.bonds = make_bonds(w.discs, s.clusters);
    } catch (const std::invalid_argument& e) {
      throw SceneError(s.file + ": clusters: " + e.what());
    }
  }
  const ShearBoxSpec& b = s.shear_box;
  if (!b.enabled) return;
  w.moving = MovingWalls{};
  w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
  for (const char* name : {"left", "right"}) {  // turning about their lower ends
    RotatingWall r;
    r.wall = wall_index(w, name);
    const Wall& wl = w.geometry.walls[r.wall];
    r.ax0 = wl.ax; r.ay0 = wl.ay; r.bx0 = wl.bx; r.by0 = wl.by;
    r.pivot_x = wl.bx;  // the walls run top -> bottom
    r.pivot_y = wl.by;
    r.reach = std::hypot(wl.ax - wl.bx, wl.ay - wl.by);
    w.moving.motion[r.wall].pivot_x = r.pivot_x;
    w.moving.motion[r.wall].pivot_y = r.pivot_y;
    w.moving.rotating.push_back(r);
  }
  RigidPlate p;
  p.wall = wall_index(w, "plate");
  const Wall& pl = w.geometry.walls[p.wall];
  p.ax0 = pl.ax; p.ay0 = pl.ay; p.bx0 = pl.bx; p.by0 = pl.by;
  p.mass = b.plate_mass;
  p.follow = b.plate_follows_walls ? 0 : -1;
  w.moving.plates.push_back(p);
}

}  // namespace dem
