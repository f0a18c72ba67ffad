#include "scene.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "fill.hpp"
#include "neighbors.hpp"
#include "stability.hpp"
#include "world.hpp"

namespace dem {

namespace {

constexpr long kMaxDiscs = 50'000'000;  // refuse absurd fills before allocating them

std::string show(const toml::node& n) {
  std::ostringstream os;
  n.visit([&](auto&& v) {
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, toml::value<std::string>>) os << '"' << v.get() << '"';
    else os << v;
  });
  std::string out = os.str();
  if (out.size() > 60) out = out.substr(0, 57) + "...";
  return out;
}

std::string show(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

// A TOML table being read: remembers the keys used so that unknown keys can be refused.
class Tab {
 public:
  Tab(const toml::table& t, std::string path, const std::string& file)
      : t_(t), path_(std::move(path)), file_(file) {}

  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  [[noreturn]] void fail(const std::string& key, const std::string& value, const std::string& why) const {
    std::string msg = file_ + ": " + field(key);
    if (!value.empty()) msg += " = " + value;
    msg += ": " + why;
    if (auto n = t_.get(key)) {
      const auto& src = n->source();
      if (src.begin.line) msg += " (line " + std::to_string(src.begin.line) + ")";
    }
    throw SceneError(msg);
  }

  bool has(const std::string& key) const { return t_.contains(key); }

  const toml::node* node(const std::string& key) {
    used_.insert(key);
    return t_.get(key);
  }

  double num(const std::string& key, const double* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    double v;
    if (auto i = n->as_integer()) v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point()) v = f->get();
    else fail(key, show(*n), "expected a number");
    if (!std::isfinite(v)) fail(key, show(*n), "must be a finite number");
    return v;
  }
  double num(const std::string& key, double def) { return num(key, &def); }
  double positive(const std::string& key, const double* def = nullptr) {
    const double v = num(key, def);
    if (!(v > 0)) fail(key, show(v), "must be > 0");
    return v;
  }
  double positive(const std::string& key, double def) { return positive(key, &def); }
  double non_negative(const std::string& key, double def) {
    const double v = num(key, &def);
    if (v < 0) fail(key, show(v), "must be >= 0");
    return v;
  }
  long integer(const std::string& key, const long* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    if (auto i = n->as_integer()) return static_cast<long>(i->get());
    fail(key, show(*n), "expected an integer");
  }
  long integer(const std::string& key, long def) { return integer(key, &def); }
  bool boolean(const std::string& key, bool def) {
    const toml::node* n = node(key);
    if (!n) return def;
    if (auto b = n->as_boolean()) return b->get();
    fail(key, show(*n), "expected true or false");
  }
  std::string str(const std::string& key, const std::string* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    if (auto s = n->as_string()) return s->get();
    fail(key, show(*n), "expected a string");
  }
  std::string str(const std::string& key, const std::string& def) { return str(key, &def); }
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string* def = nullptr) {
    const std::string v = str(key, def);
    if (std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(key, '"' + v + '"', "must be one of: " + list);
    }
    return v;
  }
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, const std::string& def) {
    return choice(key, allowed, &def);
  }
  // [x, y] of finite numbers.
  void vec2(const std::string& key, double& x, double& y, bool required = true) {
    const toml::node* n = node(key);
    if (!n) {
      if (required) fail(key, "", "required value is missing");
      return;
    }
    auto a = n->as_array();
    if (!a || a->size() != 2) fail(key, show(*n), "expected an array of two numbers [x, y]");
    double v[2];
    for (int k = 0; k < 2; ++k) {
      const toml::node& e = *a->get(k);
      if (auto i = e.as_integer()) v[k] = static_cast<double>(i->get());
      else if (auto f = e.as_floating_point()) v[k] = f->get();
      else fail(key, show(*n), "expected an array of two numbers [x, y]");
      if (!std::isfinite(v[k])) fail(key, show(*n), "must hold finite numbers");
    }
    x = v[0];
    y = v[1];
  }
  const toml::table* table(const std::string& key, bool required) {
    const toml::node* n = node(key);
    if (!n) {
      if (required) fail(key, "", "required table is missing");
      return nullptr;
    }
    if (auto t = n->as_table()) return t;
    fail(key, show(*n), "expected a table [" + field(key) + "]");
  }
  const toml::array* array_of_tables(const std::string& key) {
    const toml::node* n = node(key);
    if (!n) return nullptr;
    auto a = n->as_array();
    if (!a || !a->is_array_of_tables()) fail(key, show(*n), "expected an array of tables [[" + field(key) + "]]");
    return a;
  }
  // Refuses keys that were never asked for.
  void finish() const {
    for (const auto& [k, v] : t_) {
      const std::string key(k.str());
      if (!used_.count(key)) fail(key, show(v), "unknown key");
    }
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

int material_index(SceneSpec& s, Tab& t, const std::string& key) {
  const std::string name = t.str(key);
  for (std::size_t m = 0; m < s.material_names.size(); ++m)
    if (s.material_names[m] == name) return static_cast<int>(m);
  t.fail(key, '"' + name + '"', "no such material in [materials]");
}

// kn or kn_rho_g (the paper's X/(rho g) form, in cm or cm s): exactly one.
double pair_value(Tab& t, const std::string& key, double rho_g, bool needs_positive) {
  const bool abs = t.has(key), scaled = t.has(key + "_rho_g");
  if (abs && scaled) t.fail(key, "", "give either " + key + " or " + key + "_rho_g, not both");
  if (!abs && !scaled) t.fail(key, "", "required value is missing (or " + key + "_rho_g)");
  if (scaled && !(rho_g > 0))
    t.fail(key + "_rho_g", "", "needs a disc material with a density on one side of the pair");
  const double v = abs ? t.num(key) : t.num(key + "_rho_g") * rho_g;
  const std::string k = abs ? key : key + "_rho_g";
  if (needs_positive ? !(v > 0) : v < 0) t.fail(k, show(abs ? v : v / rho_g), needs_positive ? "must be > 0" : "must be >= 0");
  return v;
}

void read_walls(SceneSpec& s, Tab& root) {
  if (const toml::table* st = root.table("silo", false)) {
    Tab t(*st, "silo", s.file);
    s.has_silo = true;
    s.silo_width = t.positive("width", 40.0);
    s.silo_height = t.positive("height", 40.0);
    s.slit_width = t.non_negative("slit_width", 8.0);
    if (s.slit_width >= s.silo_width) t.fail("slit_width", show(s.slit_width), "must be smaller than the width");
    s.slit_open = t.choice("slit", {"closed", "open"}, "closed") == "open";
    const int wm = material_index(s, t, "wall_material");
    const int pm = t.has("point_material") ? material_index(s, t, "point_material") : wm;
    t.finish();
    const double W = s.silo_width, H = s.silo_height;
    const double L = 0.5 * (W - s.slit_width), R = 0.5 * (W + s.slit_width);
    auto& walls = s.geometry.walls;
    // Fig. 5: side walls OA and BC (run top -> bottom: positive shear = downward friction),
    // bottom AB split at the slit ends L and R, the slit LR a gate that opens.
    walls.push_back({"left", "side_left", 0, H, 0, 0, wm});
    walls.push_back({"right", "side_right", W, H, W, 0, wm});
    if (s.slit_width > 0) {
      walls.push_back({"bottom_left", "bottom", 0, 0, L, 0, wm});
      if (!s.slit_open) walls.push_back({"gate", "bottom", L, 0, R, 0, wm});
      walls.push_back({"bottom_right", "bottom", R, 0, W, 0, wm});
      s.geometry.points.push_back({"L", "slit_ends", L, 0, pm, {}});
      s.geometry.points.push_back({"R", "slit_ends", R, 0, pm, {}});
    } else {
      walls.push_back({"bottom", "bottom", 0, 0, W, 0, wm});
    }
  }
  if (const toml::array* arr = root.array_of_tables("walls")) {
    std::size_t idx = 0;
    for (const auto& e : *arr) {
      Tab t(*e.as_table(), "walls[" + std::to_string(idx++) + "]", s.file);
      Wall w;
      w.name = t.str("name");
      t.vec2("from", w.ax, w.ay);
      t.vec2("to", w.bx, w.by);
      if (std::hypot(w.bx - w.ax, w.by - w.ay) <= 0) t.fail("to", "", "the wall has zero length (from == to)");
      w.material = material_index(s, t, "material");
      w.group = t.str("group", w.name);
      t.finish();
      s.geometry.walls.push_back(w);
    }
  }
  if (const toml::array* arr = root.array_of_tables("points")) {
    std::size_t idx = 0;
    for (const auto& e : *arr) {
      Tab t(*e.as_table(), "points[" + std::to_string(idx++) + "]", s.file);
      Point p;
      p.name = t.str("name");
      t.vec2("at", p.x, p.y);
      p.material = material_index(s, t, "material");
      p.group = t.str("group", p.name);
      t.finish();
      s.geometry.points.push_back(p);
    }
  }
  std::set<std::string> names;
  for (const auto& w : s.geometry.walls)
    if (!names.insert(w.name).second) throw SceneError(s.file + ": walls: duplicated name \"" + w.name + "\"");
  for (const auto& p : s.geometry.points)
    if (!names.insert(p.name).second) throw SceneError(s.file + ": points: duplicated name \"" + p.name + "\"");
  if (s.geometry.walls.empty()) throw SceneError(s.file + ": silo / walls: the scene has no walls");
}

void read_disc_file(SceneSpec& s, Tab& t, const std::string& rel, int default_mat) {
  std::string path = rel;
  if (!rel.empty() && rel[0] != '/') {
    const auto slash = s.file.find_last_of('/');
    if (slash != std::string::npos) path = s.file.substr(0, slash + 1) + rel;
  }
  std::ifstream in(path);
  if (!in) t.fail("file", '"' + rel + '"', "cannot open " + path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  {
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) head.push_back(c);
  }
  auto col = [&](const std::string& n) {
    auto it = std::find(head.begin(), head.end(), n);
    return it == head.end() ? -1 : static_cast<int>(it - head.begin());
  };
  const int cx = col("x"), cy = col("y"), cr = col("r"), cm = col("material");
  if (cx < 0 || cy < 0 || cr < 0) t.fail("file", '"' + rel + '"', "the header must name columns x, y and r");
  long lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    auto get = [&](int k) {
      if (k >= static_cast<int>(cells.size()))
        t.fail("file", '"' + rel + '"', "line " + std::to_string(lineno) + " has too few columns");
      char* end = nullptr;
      const double v = std::strtod(cells[k].c_str(), &end);
      if (end == cells[k].c_str() || !std::isfinite(v))
        t.fail("file", '"' + rel + '"', "line " + std::to_string(lineno) + ": \"" + cells[k] + "\" is not a finite number");
      return v;
    };
    int mat = default_mat;
    if (cm >= 0 && cm < static_cast<int>(cells.size())) {
      auto it = std::find(s.material_names.begin(), s.material_names.end(), cells[cm]);
      if (it == s.material_names.end())
        t.fail("file", '"' + rel + '"', "line " + std::to_string(lineno) + ": unknown material \"" + cells[cm] + "\"");
      mat = static_cast<int>(it - s.material_names.begin());
    }
    s.discs.push_back({get(cx), get(cy), get(cr), mat});
    if (static_cast<long>(s.discs.size()) > kMaxDiscs) t.fail("file", '"' + rel + '"', "more than 5e7 discs");
  }
}

void read_fill(SceneSpec& s, Tab& root) {
  Tab t(*root.table("fill", true), "fill", s.file);
  const std::string type = t.choice("type", {"lattice", "list", "file"});
  const int mat = material_index(s, t, "material");
  if (s.density[mat] <= 0) t.fail("material", '"' + s.material_names[mat] + '"', "a disc material needs a density");
  if (type == "lattice") {
    if (!s.has_silo) t.fail("type", "\"lattice\"", "a lattice fill needs a [silo] to fill");
    LatticeSpec L;
    L.s = static_cast<int>(t.integer("s"));
    if (L.s < 2 || L.s > 1000000) t.fail("s", std::to_string(L.s), "must be between 2 and 1e6");
    L.radius = t.positive("radius", 1.0);
    L.gap = t.non_negative("gap", 0.004);
    L.rows = t.integer("rows", 0L);
    L.count = t.integer("count", 350L);
    if (L.rows < 0) t.fail("rows", std::to_string(L.rows), "must be >= 0 (0: from count)");
    if (L.count <= 0) t.fail("count", std::to_string(L.count), "must be > 0");
    if (L.rows > kMaxDiscs || L.count > kMaxDiscs) t.fail(L.rows ? "rows" : "count", std::to_string(L.rows ? L.rows : L.count), "more than 5e7 discs");
    LatticeGeometry g{};
    const std::string why = lattice_geometry(L, s.silo_width, g);
    if (!why.empty()) t.fail("s", std::to_string(L.s), why);
    if (g.n > kMaxDiscs) t.fail("rows", std::to_string(g.rows), "more than 5e7 discs");
    std::vector<double> x, y;
    lattice_centres(L, g, 0.0, 0.0, x, y);
    for (std::size_t k = 0; k < x.size(); ++k) s.discs.push_back({x[k], y[k], L.radius, mat});
    std::ostringstream os;
    os << "lattice " << L.s - 1 << "/" << L.s << ": " << g.n << " discs in " << g.rows << " rows, pitch "
       << g.pitch << ", row height " << g.row_height << ", gap " << L.gap;
    s.fill_summary = os.str();
  } else if (type == "list") {
    const toml::node* n = t.node("discs");
    if (!n) t.fail("discs", "", "required value is missing");
    auto a = n->as_array();
    if (!a) t.fail("discs", show(*n), "expected an array of [x, y, r]");
    if (static_cast<long>(a->size()) > kMaxDiscs) t.fail("discs", "", "more than 5e7 discs");
    for (std::size_t k = 0; k < a->size(); ++k) {
      auto e = a->get(k)->as_array();
      const std::string f = "discs[" + std::to_string(k) + "]";
      if (!e || e->size() != 3) t.fail(f, show(*a->get(k)), "expected [x, y, r]");
      double v[3];
      for (int c = 0; c < 3; ++c) {
        const toml::node& x = *e->get(c);
        if (auto i = x.as_integer()) v[c] = static_cast<double>(i->get());
        else if (auto fl = x.as_floating_point()) v[c] = fl->get();
        else t.fail(f, show(*e), "expected numbers [x, y, r]");
        if (!std::isfinite(v[c])) t.fail(f, show(*e), "must hold finite numbers");
      }
      s.discs.push_back({v[0], v[1], v[2], mat});
    }
    s.fill_summary = "explicit list of " + std::to_string(s.discs.size()) + " discs";
  } else {
    const std::string f = t.str("file");
    read_disc_file(s, t, f, mat);
    s.fill_summary = "file " + f + ": " + std::to_string(s.discs.size()) + " discs";
  }
  // A packing saved at rest overlaps by ~1e-3 r: accepted up to this fraction of the smaller radius.
  s.max_initial_overlap = t.non_negative("max_initial_overlap", 0.0);
  if (s.max_initial_overlap >= 0.5)
    t.fail("max_initial_overlap", show(s.max_initial_overlap), "must be < 0.5 (a fraction of the radius)");
  if (t.has("count") && type != "lattice") {
    const long c = t.integer("count");
    if (c != static_cast<long>(s.discs.size()))
      t.fail("count", std::to_string(c), "does not match the " + std::to_string(s.discs.size()) + " discs given");
  }
  t.finish();
  if (s.discs.empty()) throw SceneError(s.file + ": fill: no discs");
  for (std::size_t k = 0; k < s.discs.size(); ++k)
    if (!(s.discs[k].r > 0))
      throw SceneError(s.file + ": fill: disc " + std::to_string(k) + " radius = " + show(s.discs[k].r) + ": must be > 0");
}

}  // namespace

// Overlapping discs and discs outside the walls are refused (cell grid, no O(N^2)).
void check_initial_discs(const SceneSpec& s) {
  Discs d;
  for (const auto& c : s.discs) d.add(c.x, c.y, c.r, 1.0, c.material);
  Neighbors nb;
  nb.skin = 0;
  Geometry g = s.geometry;
  g.link_points();
  nb.rebuild(d, g);
  auto where = [&](int i) {
    std::ostringstream os;
    os.precision(10);
    os << "disc " << i << " at (" << s.discs[i].x << ", " << s.discs[i].y << ") r = " << s.discs[i].r;
    return os.str();
  };
  for (const auto& p : nb.pairs) {
    const double dx = d.x[p.j] - d.x[p.i], dy = d.y[p.j] - d.y[p.i];
    const double sum = d.r[p.i] + d.r[p.j];
    const double allowed = s.max_initial_overlap * std::min(d.r[p.i], d.r[p.j]);
    if (dx * dx + dy * dy < (sum - allowed) * (sum - allowed))
      throw SceneError(s.file + ": fill: " + where(p.i) + " overlaps " + where(p.j) +
                       (allowed > 0 ? " by more than fill.max_initial_overlap = " + show(s.max_initial_overlap) + " r"
                                    : ": initial discs must not overlap (fill.max_initial_overlap allows a rested packing's overlaps)"));
  }
  const double x0 = g.min_x(), x1 = g.max_x(), y0 = g.min_y(), y1 = g.max_y();
  for (int i = 0; i < static_cast<int>(d.size()); ++i) {
    if (d.x[i] < x0 || d.x[i] > x1 || d.y[i] < y0 || d.y[i] > std::max(y1, y0))
      throw SceneError(s.file + ": fill: " + where(i) + " is outside the walls (box [" + show(x0) + ", " + show(x1) +
                       "] x [" + show(y0) + ", " + show(y1) + "])");
  }
  for (const auto& c : nb.walls) {
    const int nw = static_cast<int>(g.walls.size());
    const double dist = obstacle_distance(g, c.k, d.x[c.i], d.y[c.i]);
    if (dist < d.r[c.i] * (1.0 - s.max_initial_overlap)) {
      const std::string name = c.k < nw ? "wall \"" + g.walls[c.k].name + "\"" : "point \"" + g.points[c.k - nw].name + "\"";
      throw SceneError(s.file + ": fill: " + where(c.i) + " overlaps " + name + ": discs must start inside the walls");
    }
  }
}


Scheme parse_scheme(const std::string& v, bool& ok) {
  ok = true;
  if (v == "paper_eq18") return Scheme::paper_eq18;
  if (v == "paper_eq19") return Scheme::paper_eq19;
  if (v == "velocity_verlet") return Scheme::velocity_verlet;
  ok = false;
  return Scheme::paper_eq19;
}

SceneSpec load_scene(const std::string& path, const SceneOverrides& ov) {
  SceneSpec s;
  s.file = path;
  toml::table root_table;
  {
    std::ifstream probe(path);
    if (!probe) throw SceneError(path + ": cannot open the scene file");
  }
  try {
    root_table = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ": TOML syntax error: " << e.description() << " (line " << e.source().begin.line << ", column "
       << e.source().begin.column << ")";
    throw SceneError(os.str());
  }
  Tab root(root_table, "", s.file);

  {
    Tab t(*root.table("scene", true), "scene", s.file);
    s.name = t.str("name");
    s.description = t.str("description", "");
    t.finish();
  }
  if (const toml::table* pt = root.table("physics", false)) {
    Tab t(*pt, "physics", s.file);
    t.vec2("gravity", s.gx, s.gy, false);
    t.finish();
  }
  {
    Tab t(*root.table("integrator", true), "integrator", s.file);
    bool ok;
    s.scheme = parse_scheme(t.choice("scheme", {"paper_eq18", "paper_eq19", "velocity_verlet"}), ok);
    s.dt = t.positive("dt");
    s.force_dt = t.boolean("force_dt", false);
    t.finish();
  }
  if (const toml::table* ct = root.table("contact", false)) {
    Tab t(*ct, "contact", s.file);
    s.contact.normal_spring = t.choice("normal_spring", {"incremental", "overlap"}, "incremental") == "overlap"
                                  ? NormalSpring::overlap : NormalSpring::incremental;
    const std::string nt = t.choice("no_tension", {"elastic", "total", "overlap"}, "elastic");
    s.contact.no_tension = nt == "elastic" ? NoTension::elastic : nt == "total" ? NoTension::total : NoTension::overlap;
    s.contact.friction_cap = t.choice("friction_cap", {"elastic", "total"}, "elastic") == "total"
                                 ? FrictionCap::total : FrictionCap::elastic;
    t.finish();
  }
  {
    const toml::table* mt = root.table("materials", true);
    Tab t(*mt, "materials", s.file);
    for (const auto& [k, v] : *mt) {
      const std::string name(k.str());
      Tab m(*t.table(name, true), "materials." + name, s.file);
      s.material_names.push_back(name);
      s.density.push_back(m.has("density") ? m.positive("density") : 0.0);
      m.finish();
    }
    if (s.material_names.empty()) t.fail("materials", "", "no material defined");
    t.finish();
  }
  const int nm = static_cast<int>(s.material_names.size());
  s.props.assign(nm * nm, PairProps{});
  s.props_set.assign(nm * nm, 0);
  const double g = std::hypot(s.gx, s.gy);
  if (const toml::array* arr = root.array_of_tables("pairs")) {
    std::size_t idx = 0;
    for (const auto& e : *arr) {
      Tab t(*e.as_table(), "pairs[" + std::to_string(idx++) + "]", s.file);
      const toml::node* mn = t.node("materials");
      if (!mn) t.fail("materials", "", "required value is missing");
      auto a = mn->as_array();
      if (!a || a->size() != 2 || !a->get(0)->is_string() || !a->get(1)->is_string())
        t.fail("materials", show(*mn), "expected two material names [\"a\", \"b\"]");
      int ids[2];
      for (int c = 0; c < 2; ++c) {
        const std::string name = a->get(c)->as_string()->get();
        auto it = std::find(s.material_names.begin(), s.material_names.end(), name);
        if (it == s.material_names.end()) t.fail("materials", show(*mn), "no material \"" + name + "\" in [materials]");
        ids[c] = static_cast<int>(it - s.material_names.begin());
      }
      const double rho = std::max(s.density[ids[0]], s.density[ids[1]]);
      if (s.density[ids[0]] > 0 && s.density[ids[1]] > 0 && s.density[ids[0]] != s.density[ids[1]] &&
          (t.has("kn_rho_g") || t.has("ks_rho_g") || t.has("eta_n_rho_g") || t.has("eta_s_rho_g")))
        t.fail("materials", show(*mn), "the X_rho_g form is ambiguous for two densities: give absolute values");
      PairProps p;
      p.kn = pair_value(t, "kn", rho * g, true);
      p.ks = pair_value(t, "ks", rho * g, false);
      p.eta_n = pair_value(t, "eta_n", rho * g, false);
      p.eta_s = pair_value(t, "eta_s", rho * g, false);
      p.mu = t.num("mu");
      if (p.mu < 0) t.fail("mu", show(p.mu), "must be >= 0");
      t.finish();
      for (int c = 0; c < 2; ++c) {
        const int ab = ids[c] * nm + ids[1 - c];
        if (s.props_set[ab] && c == 0) t.fail("materials", show(*mn), "this pair is defined twice");
        s.props[ab] = p;
        s.props_set[ab] = 1;
      }
    }
  }
  read_walls(s, root);
  read_fill(s, root);
  {
    Tab t(*root.table("end", true), "end", s.file);
    s.end_time = t.positive("time");
    s.stop_at_rest = t.boolean("stop_at_rest", true);
    s.rest_factor = t.positive("rest_factor", 1e-4);
    s.max_overlap_fraction = t.positive("max_overlap", 0.5);
    t.finish();
  }
  double rmean = 0;
  for (const auto& d : s.discs) rmean += d.r;
  rmean /= s.discs.size();
  s.skin = 0.2 * rmean;
  if (const toml::table* nt = root.table("neighbor", false)) {
    Tab t(*nt, "neighbor", s.file);
    s.skin = t.positive("skin", s.skin);
    s.cell = t.non_negative("cell", 0.0);
    t.finish();
  }
  if (const toml::table* st = root.table("start", false)) {
    Tab t(*st, "start", s.file);
    s.start_from = t.str("from");
    const auto slash = s.file.find_last_of('/');
    if (!s.start_from.empty() && s.start_from[0] != '/' && slash != std::string::npos)
      s.start_from = s.file.substr(0, slash + 1) + s.start_from;
    t.finish();
  }
  if (const toml::table* dt = root.table("discharge", false)) {
    Tab t(*dt, "discharge", s.file);
    DischargeSpec& d = s.discharge;
    d.enabled = true;
    d.time = t.positive("time", d.time);
    d.gate = t.str("gate", d.gate);
    d.outlet_depth = t.positive("outlet_depth", d.outlet_depth);
    d.jam_time = t.positive("jam_time", d.jam_time);
    d.remove_keystone = t.choice("on_jam", {"stop", "remove_keystone"}, "stop") == "remove_keystone";
    d.series_interval = t.positive("series_interval", d.series_interval);
    d.peak_window = t.positive("peak_window", d.peak_window);
    d.surface_column = t.positive("surface_column", d.surface_column);
    if (const toml::node* n = t.node("snapshots")) {
      auto a = n->as_array();
      if (!a) t.fail("snapshots", show(*n), "expected an array of times [s]");
      d.snapshots.clear();
      for (std::size_t k = 0; k < a->size(); ++k) {
        const toml::node& e = *a->get(k);
        double v;
        if (auto i = e.as_integer()) v = static_cast<double>(i->get());
        else if (auto f = e.as_floating_point()) v = f->get();
        else t.fail("snapshots", show(*n), "expected numbers");
        if (!(v >= 0) || !std::isfinite(v)) t.fail("snapshots", show(*n), "times must be finite and >= 0");
        d.snapshots.push_back(v);
      }
      std::sort(d.snapshots.begin(), d.snapshots.end());
    }
    t.finish();
    bool found = false;
    for (const auto& w : s.geometry.walls) found |= w.name == d.gate;
    if (!found) throw SceneError(s.file + ": discharge.gate = \"" + d.gate + "\": no wall of that name (a [silo] with slit = \"closed\" has \"gate\")");
  }
  s.profile_bin = 2 * rmean;
  if (const toml::table* ot = root.table("output", false)) {
    Tab t(*ot, "output", s.file);
    s.profile_bin = t.positive("profile_bin", s.profile_bin);
    s.progress = t.boolean("progress", true);
    t.finish();
  }
  root.finish();

  // Every pair that can meet needs constants.
  std::vector<char> disc_mat(nm, 0), obst_mat(nm, 0);
  for (const auto& d : s.discs) disc_mat[d.material] = 1;
  for (const auto& w : s.geometry.walls) obst_mat[w.material] = 1;
  for (const auto& p : s.geometry.points) obst_mat[p.material] = 1;
  for (int a = 0; a < nm; ++a)
    for (int b = 0; b < nm; ++b)
      if (disc_mat[a] && (disc_mat[b] || obst_mat[b]) && !s.props_set[a * nm + b])
        throw SceneError(s.file + ": pairs: no [[pairs]] entry for materials [\"" + s.material_names[a] + "\", \"" +
                         s.material_names[b] + "\"]: every pair that can touch needs kn, ks, eta_n, eta_s, mu");

  if (ov.dt > 0) s.dt = ov.dt;
  if (!ov.scheme.empty()) {
    bool ok;
    s.scheme = parse_scheme(ov.scheme, ok);
    if (!ok) throw SceneError("--scheme " + ov.scheme + ": must be paper_eq18, paper_eq19 or velocity_verlet");
  }
  if (ov.end_time > 0) s.end_time = ov.end_time;
  if (ov.force_dt) s.force_dt = true;
  if (!ov.from.empty()) s.start_from = ov.from;
  check_initial_discs(s);
  return s;
}

void build_world(const SceneSpec& s, World& w) {
  w = World{};
  w.n_materials = static_cast<int>(s.material_names.size());
  w.props = s.props;
  w.options = s.contact;
  w.scheme = s.scheme;
  w.dt = s.dt;
  w.gx = s.gx;
  w.gy = s.gy;
  w.geometry = s.geometry;
  w.geometry.link_points();
  for (const auto& d : s.discs) w.discs.add(d.x, d.y, d.r, s.density[d.material], d.material);
  w.neighbors.skin = s.skin;
  w.neighbors.min_cell = s.cell;
  const StabilityReport rep = stability_report(w, s.material_names);
  if (s.dt > rep.dt_bound && !s.force_dt) {
    std::ostringstream os;
    os.precision(4);
    os << s.file << ": integrator.dt = " << s.dt << ": above the stability bound " << rep.dt_bound << " s of "
       << to_string(s.scheme) << " (set by " << rep.limited_by
       << "); set integrator.force_dt = true (or --force-dt) to run it anyway";
    throw SceneError(os.str());
  }
  w.init();
}

}  // namespace dem
