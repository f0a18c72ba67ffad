#include "scene/shear_scene.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "physics/world.hpp"

namespace dem {

namespace {

std::string show(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

// One table: typed reads with defaults, refusal of unknown keys, messages naming the field.
class Keys {
 public:
  Keys(const toml::table& t, std::string path, const std::string& file) : t_(t), path_(std::move(path)), file_(file) {}

  [[noreturn]] void fail(const std::string& key, const std::string& value, const std::string& why) const {
    std::string msg = file_ + ": " + path_ + "." + key;
    if (!value.empty()) msg += " = " + value;
    msg += ": " + why;
    if (auto n = t_.get(key))
      if (n->source().begin.line) msg += " (line " + std::to_string(n->source().begin.line) + ")";
    throw SceneError(msg);
  }
  const toml::node* node(const std::string& key) {
    used_.insert(key);
    return t_.get(key);
  }
  double num(const std::string& key, double def, bool positive, bool non_negative = false) {
    const toml::node* n = node(key);
    if (!n) return def;
    double v;
    if (auto i = n->as_integer()) v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point()) v = f->get();
    else fail(key, text(*n), "expected a number");
    if (!std::isfinite(v) || std::abs(v) > 1e15) fail(key, text(*n), "must be a finite number of magnitude <= 1e15");
    if (positive && !(v > 0)) fail(key, show(v), "must be > 0");
    if (non_negative && v < 0) fail(key, show(v), "must be >= 0");
    return v;
  }
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, const std::string& def) {
    const toml::node* n = node(key);
    if (!n) return def;
    auto s = n->as_string();
    if (!s) fail(key, text(*n), "expected a string");
    if (std::find(allowed.begin(), allowed.end(), s->get()) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(key, '"' + s->get() + '"', "must be one of: " + list);
    }
    return s->get();
  }
  int material(const SceneSpec& s, const std::string& key, int def) {
    const toml::node* n = node(key);
    if (!n) {
      if (def >= 0) return def;
      fail(key, "", "required value is missing");
    }
    auto v = n->as_string();
    if (!v) fail(key, text(*n), "expected a material name");
    for (std::size_t m = 0; m < s.material_names.size(); ++m)
      if (s.material_names[m] == v->get()) return static_cast<int>(m);
    fail(key, '"' + v->get() + '"', "no such material in [materials]");
  }
  std::vector<double> numbers(const std::string& key, const std::vector<double>& def) {
    const toml::node* n = node(key);
    if (!n) return def;
    auto a = n->as_array();
    if (!a) fail(key, text(*n), "expected an array of numbers");
    if (a->size() > 10000) fail(key, "", "more than 10000 entries");
    std::vector<double> out;
    for (const auto& e : *a) {
      double v;
      if (auto i = e.as_integer()) v = static_cast<double>(i->get());
      else if (auto f = e.as_floating_point()) v = f->get();
      else fail(key, text(*n), "expected an array of numbers");
      if (!(v >= 0) || !std::isfinite(v)) fail(key, text(*n), "values must be finite and >= 0");
      out.push_back(v);
    }
    std::sort(out.begin(), out.end());
    return out;
  }
  void finish() const {
    for (const auto& [k, v] : t_) {
      const std::string key(k.str());
      if (!used_.count(key)) fail(key, text(v), "unknown key");
    }
  }
  static std::string text(const toml::node& n) {
    std::ostringstream os;
    n.visit([&](auto&& v) { os << v; });
    std::string out = os.str();
    return out.size() > 60 ? out.substr(0, 57) + "..." : out;
  }
  const std::string& file() const { return file_; }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

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
    Keys t(*tt, "shear_box", s.file);
    b.enabled = true;
    b.width = t.num("width", b.width, true);
    b.height = t.num("height", b.height, true);
    b.wall_length = t.num("wall_length", 1.5 * b.height, true);
    if (b.wall_length < b.height) t.fail("wall_length", show(b.wall_length), "must be >= height = " + show(b.height));
    b.wall_material = t.material(s, "wall_material", -1);
    b.plate_material = t.material(s, "plate_material", b.wall_material);
    b.plate_volume = t.num("plate_volume", b.plate_volume, false, true);
    b.plate_density = t.num("plate_density", 0.0, false, true);
    b.plate_gap = t.num("plate_gap", b.plate_gap, false, true);
    b.plate_overhang = t.num("plate_overhang", b.plate_overhang, false, true);
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
    Keys t(*tt, "shear", s.file);
    if (!b.enabled) t.fail("rate", "", "[shear] needs a [shear_box]");
    b.shear = true;
    b.rate = t.num("rate", b.rate, true);
    b.max_strain = t.num("max_strain", b.max_strain, true);
    if (b.max_strain > 1) t.fail("max_strain", show(b.max_strain), "must be <= 1 (45 degrees)");
    b.sample_strain = t.num("sample_strain", b.sample_strain, true);
    if (b.max_strain / b.sample_strain > 1e6) t.fail("sample_strain", show(b.sample_strain), "gives more than 1e6 samples");
    b.snapshots = t.numbers("snapshots", b.snapshots);
    t.finish();
  }
  if (const toml::table* tt = table(root, "clusters", s.file)) {
    Keys t(*tt, "clusters", s.file);
    ClusterSpec& c = s.clusters;
    c.enabled = true;
    c.bonds = t.choice("bonds", {"all", "touching"}, "all") == "all" ? BondSet::all : BondSet::touching;
    c.touch_tolerance = t.num("touch_tolerance", c.touch_tolerance, false, true);
    const toml::node* n = t.node("members");
    if (!n) t.fail("members", "", "required value is missing");
    auto a = n->as_array();
    if (!a) t.fail("members", Keys::text(*n), "expected an array of disc-index arrays [[0, 1, 2], ...]");
    for (std::size_t k = 0; k < a->size(); ++k) {
      auto e = a->get(k)->as_array();
      const std::string f = "members[" + std::to_string(k) + "]";
      if (!e) t.fail(f, Keys::text(*a->get(k)), "expected an array of disc indices");
      if (e->size() < 2 || e->size() > 1000) t.fail(f, Keys::text(*e), "a cluster has 2 to 1000 discs");
      std::vector<int> m;
      for (const auto& x : *e) {
        auto i = x.as_integer();
        if (!i) t.fail(f, Keys::text(*e), "expected integer disc indices (0-based, fill order)");
        if (i->get() < 0 || i->get() > 2'000'000'000L) t.fail(f, Keys::text(*e), "disc indices must be >= 0");
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
                     " cm, the plate must start below the walls' top");
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
