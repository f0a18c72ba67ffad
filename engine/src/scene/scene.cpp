#include "scene/scene.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <system_error>

#include <unistd.h>

#include "scene/fill.hpp"
#include "scene/scene_set.hpp"
#include "scene/scene_table.hpp"
#include "scene/toml_reader.hpp"
#include "physics/free_heap.hpp"
#include "physics/neighbors.hpp"
#include "scene/shear_scene.hpp"
#include "physics/stability.hpp"
#include "physics/world.hpp"

namespace dem {

namespace {

// A limit as written in docs/scene.md: 5e7, 1e15, 2e4.
std::string limit_text(double v) {
  int e = 0;
  double m = v;
  while (m >= 10 && m == std::floor(m / 10) * 10) {
    m /= 10;
    ++e;
  }
  return e >= 3 ? show(m) + "e" + std::to_string(e) : show(v);
}

// A regular file (not a directory, device or pipe that would never end) of at most max_bytes.
std::string regular_file_problem(const std::string& path, double max_bytes) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) return "cannot open " + path;
  if (!std::filesystem::is_regular_file(st)) return path + " is not a regular file";
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return "cannot open " + path;
  if (static_cast<double>(size) > max_bytes)
    return path + " has " + std::to_string(size) + " bytes, more than the limit of " + limit_text(max_bytes);
  return "";
}

// Physical memory of this machine in bytes (0 when unknown).
double physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

// Refuses a fill of n discs beyond the disc limit or this machine's memory, before allocating it.
void check_disc_budget(const SceneSpec& s, Tab& t, const std::string& key, const std::string& value, double n) {
  if (n > static_cast<double>(s.max_discs))
    t.fail(key, value, "gives " + show(n) + " discs, more than the limit of " + limit_text(static_cast<double>(s.max_discs)) +
                           " discs (docs/scene.md, Limits)");
  const double need = n * kBytesPerDisc, have = physical_memory();
  if (have > 0 && need > have) {
    std::ostringstream os;
    os.precision(3);
    os << "gives " << n << " discs, which need about " << need / 1e9 << " GB of memory (about " << kBytesPerDisc / 1024
       << " kB per disc), more than this machine's " << have / 1e9 << " GB";
    t.fail(key, value, os.str());
  }
}

// A coordinate, radius or size within +-kMaxCoordinate (squares and sums of squares stay finite).
void check_coordinate(Tab& t, const std::string& key, const std::string& value, double v) {
  if (!(std::abs(v) <= kMaxCoordinate))
    t.fail(key, value, "beyond the limit of " + limit_text(kMaxCoordinate) + " in magnitude (docs/scene.md, Limits)");
}

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
  if (!std::isfinite(v)) t.fail(k, show(abs ? v : t.num(k)), "gives a non-finite value (too large)");
  if (needs_positive ? !(v > 0) : v < 0) t.fail(k, show(abs ? v : v / rho_g), needs_positive ? "must be > 0" : "must be >= 0");
  return v;
}

void read_walls(SceneSpec& s, Tab& root) {
  if (const toml::table* st = root.table("silo", false)) {
    Tab t(*st, "silo", s.file);
    s.has_silo = true;
    s.silo_width = t.positive("width", default_length(s.units, 40.0));
    s.silo_height = t.positive("height", default_length(s.units, 40.0));
    check_coordinate(t, "width", show(s.silo_width), s.silo_width);
    check_coordinate(t, "height", show(s.silo_height), s.silo_height);
    s.slit_width = t.non_negative("slit_width", default_length(s.units, 8.0));
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
      for (double v : {w.ax, w.ay}) check_coordinate(t, "from", show(v), v);
      for (double v : {w.bx, w.by}) check_coordinate(t, "to", show(v), v);
      if (std::hypot(w.bx - w.ax, w.by - w.ay) <= 0) t.fail("to", "", "the wall has zero length (from == to)");
      w.material = material_index(s, t, "material");
      w.group = t.str("group", w.name);
      // A prescribed translation: velocity [cm/s] while move_from <= t <= move_until [s].
      if (t.has("velocity") || t.has("move_from") || t.has("move_until")) {
        t.vec2("velocity", w.move_vx, w.move_vy);
        w.move_from = t.non_negative("move_from", 0.0);
        w.move_until = t.positive("move_until");
        if (!(w.move_until > w.move_from))
          t.fail("move_until", show(w.move_until), "must be later than move_from = " + show(w.move_from));
        const double span = w.move_until - w.move_from;
        for (double v : {w.move_vx * span, w.move_vy * span}) check_coordinate(t, "velocity", show(v) + " " + unit_names(s.units).length + " of travel", v);
        for (double v : {w.ax + w.move_vx * span, w.ay + w.move_vy * span, w.bx + w.move_vx * span, w.by + w.move_vy * span})
          check_coordinate(t, "velocity", "an end at " + show(v) + " " + unit_names(s.units).length, v);
      }
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
      for (double v : {p.x, p.y}) check_coordinate(t, "at", show(v), v);
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
  const std::string problem = regular_file_problem(path, 1e18);  // lines and discs are limited below
  if (!problem.empty()) t.fail("file", '"' + rel + '"', problem);
  std::ifstream in(path);
  if (!in) t.fail("file", '"' + rel + '"', "cannot open " + path);
  std::string line;
  long lines_read = 0;
  // Lines of at most 4096 characters: a file without line breaks is not read into memory whole.
  auto next_line = [&]() {
    line.clear();
    ++lines_read;
    for (int c; (c = in.get()) != std::char_traits<char>::eof();) {
      if (c == '\n') return true;
      if (line.size() >= 4096)
        t.fail("file", '"' + rel + '"', "line " + std::to_string(lines_read) + " is longer than 4096 characters");
      line.push_back(static_cast<char>(c));
    }
    return !line.empty();
  };
  next_line();
  if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF files
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
  const bool with_v = t.boolean("velocities", false);  // start from the file's vx, vy, omega
  const int cvx = col("vx"), cvy = col("vy"), cw = col("omega");
  if (with_v && (cvx < 0 || cvy < 0 || cw < 0))
    t.fail("velocities", "true", "the file's header must name columns vx, vy and omega");
  long lineno = 1;
  while (next_line()) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
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
    if (with_v) {
      s.discs.back().vx = get(cvx);
      s.discs.back().vy = get(cvy);
      s.discs.back().omega = get(cw);
    }
    if (static_cast<long>(s.discs.size()) > s.max_discs)
      check_disc_budget(s, t, "file", '"' + rel + '"', static_cast<double>(s.discs.size()));
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
    const long s_row = t.integer("s");
    if (s_row < 2 || s_row > 1000000) t.fail("s", std::to_string(s_row), "must be between 2 and 1e6");
    L.s = static_cast<int>(s_row);
    L.radius = t.positive("radius", default_length(s.units, 1.0));
    L.gap = t.non_negative("gap", default_length(s.units, 0.004));
    check_coordinate(t, "radius", show(L.radius), L.radius);
    check_coordinate(t, "gap", show(L.gap), L.gap);
    L.rows = t.integer("rows", 0L);
    L.count = t.integer("count", 350L);
    if (L.rows < 0) t.fail("rows", std::to_string(L.rows), "must be >= 0 (0: from count)");
    if (L.count <= 0) t.fail("count", std::to_string(L.count), "must be > 0");
    // A first bound keeps the row arithmetic exact; the disc count is checked below.
    if (L.rows > s.max_discs || L.count > s.max_discs)
      t.fail(L.rows > s.max_discs ? "rows" : "count", std::to_string(L.rows > s.max_discs ? L.rows : L.count),
             "more than the limit of " + limit_text(static_cast<double>(s.max_discs)) + " discs (docs/scene.md, Limits)");
    LatticeGeometry g{};
    const std::string why = lattice_geometry(L, s.silo_width, g);
    if (!why.empty()) t.fail("s", std::to_string(L.s), why);
    check_disc_budget(s, t, L.rows > 0 ? "rows" : "count", std::to_string(L.rows > 0 ? L.rows : L.count),
                      static_cast<double>(g.n));
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
    check_disc_budget(s, t, "discs", "", static_cast<double>(a->size()));
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
  s.discs.shrink_to_fit();  // read by push_back: up to 2x its length, alive until the world is built
  check_disc_budget(s, t, "type", '"' + type + '"', static_cast<double>(s.discs.size()));
  check_disc_values(s);
}

}  // namespace

// Each disc's radius, place, mass and start motion: finite, inside the limits (docs/scene.md).
void check_disc_values(const SceneSpec& s) {
  for (std::size_t k = 0; k < s.discs.size(); ++k) {
    const DiscInit& d = s.discs[k];
    const std::string disc = s.file + ": fill: disc " + std::to_string(k);
    if (!(d.r > 0)) throw SceneError(disc + " radius = " + show(d.r) + ": must be > 0");
    if (!(std::isfinite(d.vx) && std::isfinite(d.vy) && std::isfinite(d.omega)))
      throw SceneError(disc + " velocity (" + show(d.vx) + ", " + show(d.vy) + "), omega " + show(d.omega) +
                       ": must be finite");
    for (double v : {d.x, d.y, d.r})
      if (!(std::abs(v) <= kMaxCoordinate))
        throw SceneError(disc + " at (" + show(d.x) + ", " + show(d.y) + ") r = " + show(d.r) + ": beyond the limit of " +
                         limit_text(kMaxCoordinate) + " in magnitude (docs/scene.md, Limits)");
    // m = rho pi r^2 and I = m r^2 / 2 must be finite and > 0 (1/m and 1/I are used).
    const double m = s.density[d.material] * 3.14159265358979323846 * d.r * d.r, inertia = 0.5 * m * d.r * d.r;
    if (!(m > 0 && std::isfinite(m) && inertia > 0 && std::isfinite(inertia) && std::isfinite(1 / inertia)))
      throw SceneError(disc + " radius = " + show(d.r) + ", materials." + s.material_names[d.material] + ".density = " +
                       show(s.density[d.material]) + ": mass " + show(m) + " or moment of inertia " + show(inertia) +
                       " is not a finite number > 0");
  }
}

// Overlapping discs and discs outside the walls are refused (cell grid, no O(N^2)).
void check_initial_discs(const SceneSpec& s) {
  Discs d;  // what the contact search reads, beside the scene's own list (at 1M discs the run's peak)
  d.reserve_positions(s.discs.size());
  for (const auto& c : s.discs) d.add_position(c.x, c.y, c.r, 1.0, c.material);
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
    const double sum = d.r(p.i) + d.r(p.j);
    const double allowed = s.max_initial_overlap * std::min(d.r(p.i), d.r(p.j));
    if (dx * dx + dy * dy < (sum - allowed) * (sum - allowed))
      throw SceneError(s.file + ": fill: " + where(p.i) + " overlaps " + where(p.j) +
                       (allowed > 0 ? " by more than fill.max_initial_overlap = " + show(s.max_initial_overlap) + " r"
                                    : ": initial discs must not overlap (fill.max_initial_overlap allows a rested packing's overlaps)"));
  }
  const double x0 = g.min_x(), x1 = g.max_x(), y0 = g.min_y(), y1 = g.max_y();
  for (int i = 0; i < static_cast<int>(d.size()); ++i) {
    // Only along a direction the walls span: a lone floor does not bound the height.
    const bool out_x = x1 > x0 && (d.x[i] < x0 || d.x[i] > x1);
    const bool out_y = y1 > y0 && (d.y[i] < y0 || d.y[i] > y1);
    if (out_x || out_y)
      throw SceneError(s.file + ": fill: " + where(i) + " is outside the walls (box [" + show(x0) + ", " + show(x1) +
                       "] x [" + show(y0) + ", " + show(y1) + "])");
  }
  for (const auto& c : nb.walls) {
    const int nw = static_cast<int>(g.walls.size());
    const double dist = obstacle_distance(g, c.k, d.x[c.i], d.y[c.i]);
    if (dist < d.r(c.i) * (1.0 - s.max_initial_overlap)) {
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
  if (v == "velocity_verlet_onset") return Scheme::velocity_verlet_onset;
  ok = false;
  return Scheme::paper_eq19;
}

toml::table parse_scene_file(const std::string& path) {
  toml::table root_table;
  {
    std::ifstream probe(path);
    if (!probe) throw SceneError(path + ": cannot open the scene file");
    const std::string problem = regular_file_problem(path, kMaxSceneBytes);
    if (!problem.empty()) throw SceneError(path + ": " + problem);
  }
  try {
    root_table = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ": TOML syntax error: " << e.description() << " (line " << e.source().begin.line << ", column "
       << e.source().begin.column << ")";
    throw SceneError(os.str());
  }
  return root_table;
}

namespace {

// [scene], [physics], [integrator], [contact].
void read_run_tables(SceneSpec& s, Tab& root) {
  {
    Tab t(*root.table("scene", true), "scene", s.file);
    s.name = t.str("name");
    s.description = t.str("description", "");
    t.finish();
  }
  if (const toml::table* pt = root.table("physics", false)) {
    Tab t(*pt, "physics", s.file);
    // The unit system first: gravity's default (and the other defaults with a unit) follow it.
    s.units = t.choice("units", {"cgs", "si"}, "cgs") == "si" ? Units::si : Units::cgs;
    s.gy = default_gravity_y(s.units);
    t.vec2("gravity", s.gx, s.gy, false);
    if (!std::isfinite(std::hypot(s.gx, s.gy))) t.fail("gravity", "", "its magnitude is not a finite number");
    t.finish();
  }
  {
    Tab t(*root.table("integrator", true), "integrator", s.file);
    bool ok;
    s.scheme = parse_scheme(t.choice("scheme", {"paper_eq18", "paper_eq19", "velocity_verlet", "velocity_verlet_onset"}), ok);
    s.dt = t.positive("dt");
    s.force_dt = t.boolean("force_dt", false);
    const long th = t.integer("threads", 1L);
    if (th < 1 || th > kMaxThreads) t.fail("threads", std::to_string(th), "must be an integer in [1, " + std::to_string(kMaxThreads) + "]");
    s.threads = static_cast<int>(th);
    s.disc_order = t.choice("disc_order", {"auto", "off"}, "auto") == "off" ? DiscOrder::off : DiscOrder::automatic;
    s.thread_choice = t.choice("thread_choice", {"auto", "off"}, "auto") == "auto";
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
    s.contact.lever_arm = t.choice("lever_arm", {"radius", "contact_point"}, "radius") == "contact_point"
                              ? LeverArm::contact_point : LeverArm::radius;
    t.finish();
  }
}

// [materials]: names and densities.
void read_materials(SceneSpec& s, Tab& root) {
  {
    const toml::table* mt = root.table("materials", true);
    Tab t(*mt, "materials", s.file);
    if (static_cast<long>(mt->size()) > kMaxMaterials)
      throw SceneError(s.file + ": materials: " + std::to_string(mt->size()) + " materials, more than the limit of " +
                       std::to_string(kMaxMaterials) + " (docs/scene.md, Limits)");
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
}

// [[pairs]]: the contact constants of each material pair (Table 2 or absolute).
void read_pairs(SceneSpec& s, Tab& root) {
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
}

// [end] and [neighbor] (the skin defaults to 0.2 mean radii).
void read_end_and_neighbor(SceneSpec& s, Tab& root) {
  {
    Tab t(*root.table("end", true), "end", s.file);
    s.end_time = t.positive("time");
    s.stop_at_rest = t.boolean("stop_at_rest", true);
    s.rest_factor = t.positive("rest_factor", 1e-4);
    s.max_overlap_fraction = t.positive("max_overlap", 0.5);
    s.max_energy_gain = t.positive("max_energy_gain", 0.05);
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
    double rmax = 0;
    for (const auto& d : s.discs) rmax = std::max(rmax, d.r);
    // A longer reach would pair every disc with every other (memory ~ N^2), a larger cell
    // would search them all (time ~ N^2).
    if (s.skin > 2 * rmax) t.fail("skin", show(s.skin), "must be <= 2 r_max = " + show(2 * rmax) + " (one diameter)");
    if (s.cell > 10 * (2 * rmax + s.skin))
      t.fail("cell", show(s.cell), "must be <= 10 (2 r_max + skin) = " + show(10 * (2 * rmax + s.skin)));
    t.finish();
  }
}

// [start] from: a state file, relative to the scene file.
void read_start(SceneSpec& s, Tab& root) {
  if (const toml::table* st = root.table("start", false)) {
    Tab t(*st, "start", s.file);
    s.start_from = t.str("from");
    const auto slash = s.file.find_last_of('/');
    if (!s.start_from.empty() && s.start_from[0] != '/' && slash != std::string::npos)
      s.start_from = s.file.substr(0, slash + 1) + s.start_from;
    t.finish();
  }
}

// [discharge] (section 5(2)).
void read_discharge(SceneSpec& s, Tab& root) {
  if (const toml::table* dt = root.table("discharge", false)) {
    Tab t(*dt, "discharge", s.file);
    DischargeSpec& d = s.discharge;
    d.enabled = true;
    d.time = t.positive("time", d.time);
    d.gate = t.str("gate", d.gate);
    d.outlet_depth = t.positive("outlet_depth", default_length(s.units, d.outlet_depth));
    d.jam_time = t.positive("jam_time", d.jam_time);
    d.remove_keystone = t.choice("on_jam", {"stop", "remove_keystone"}, "stop") == "remove_keystone";
    d.series_interval = t.positive("series_interval", d.series_interval);
    d.peak_window = t.positive("peak_window", d.peak_window);
    d.surface_column = t.positive("surface_column", default_length(s.units, d.surface_column));
    if (const toml::node* n = t.node("snapshots")) {
      auto a = n->as_array();
      if (!a) t.fail("snapshots", show(*n), "expected an array of times [s]");
      if (static_cast<long>(a->size()) > kMaxSnapshots)
        t.fail("snapshots", std::to_string(a->size()) + " times", "more than the limit of " + limit_text(kMaxSnapshots));
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
}

// [output] (the profile bin defaults to one mean diameter).
void read_output(SceneSpec& s, Tab& root) {
  double rmean = 0;
  for (const auto& d : s.discs) rmean += d.r;
  rmean /= s.discs.size();
  s.profile_bin = 2 * rmean;
  if (const toml::table* ot = root.table("output", false)) {
    Tab t(*ot, "output", s.file);
    s.profile_bin = t.positive("profile_bin", s.profile_bin);
    for (const Wall& w : s.geometry.walls) {
      const double bins = std::hypot(w.bx - w.ax, w.by - w.ay) / s.profile_bin;
      if (!(bins <= kMaxProfileBins))
        t.fail("profile_bin", show(s.profile_bin), "gives " + show(bins) + " bins on wall \"" + w.name +
                                                       "\", more than the limit of " + limit_text(kMaxProfileBins));
    }
    s.progress = t.boolean("progress", true);
    s.rotation_angle = t.boolean("rotation_angle", false);
    s.checkpoint_every = t.non_negative("checkpoint_every", 0.0);
    s.thermo_interval = t.positive("thermo_interval", s.thermo_interval);
    s.snapshot_interval = t.non_negative("snapshot_interval", 0.0);
    s.progress_interval = t.non_negative("progress_interval", s.progress_interval);
    const std::string vtu = t.choice("vtu", {"auto", "ascii", "binary", "none"}, "auto");
    s.vtu = vtu == "ascii"    ? VtuChoice::ascii
            : vtu == "binary" ? VtuChoice::binary
            : vtu == "none"   ? VtuChoice::none
                              : VtuChoice::automatic;
    t.finish();
  }
}

// Every pair that can meet needs constants.
void check_pairs_complete(const SceneSpec& s) {
  const int nm = static_cast<int>(s.material_names.size());
  std::vector<char> disc_mat(nm, 0), obst_mat(nm, 0);
  for (const auto& d : s.discs) disc_mat[d.material] = 1;
  for (const auto& w : s.geometry.walls) obst_mat[w.material] = 1;
  for (const auto& p : s.geometry.points) obst_mat[p.material] = 1;
  for (int a = 0; a < nm; ++a)
    for (int b = 0; b < nm; ++b)
      if (disc_mat[a] && (disc_mat[b] || obst_mat[b]) && !s.props_set[a * nm + b])
        throw SceneError(s.file + ": pairs: no [[pairs]] entry for materials [\"" + s.material_names[a] + "\", \"" +
                         s.material_names[b] + "\"]: every pair that can touch needs kn, ks, eta_n, eta_s, mu");

}

// The command line's overrides, then the step-count limits and the state file.
void apply_overrides(SceneSpec& s, const SceneOverrides& ov) {
  if (ov.dt > 0) s.dt = ov.dt;
  if (!ov.scheme.empty()) {
    bool ok;
    s.scheme = parse_scheme(ov.scheme, ok);
    if (!ok) throw SceneError("--scheme " + ov.scheme + ": must be paper_eq18, paper_eq19, velocity_verlet or velocity_verlet_onset");
  }
  // Its onset fraction reads the overlap (onset.cpp): the incremental spring has no such state.
  if (s.scheme == Scheme::velocity_verlet_onset && s.contact.normal_spring != NormalSpring::overlap)
    throw SceneError(s.file + ": integrator.scheme = \"velocity_verlet_onset\" needs contact.normal_spring = \"overlap\"");
  if (ov.end_time > 0) s.end_time = ov.end_time;
  if (ov.force_dt) s.force_dt = true;
  if (ov.no_vtu) s.vtu = VtuChoice::none;
  if (ov.threads > 0) s.threads = ov.threads;
  if (!ov.from.empty()) s.start_from = ov.from;
  // Step counts are integers: a time that is too many steps of dt is refused.
  auto steps_limit = [&](const std::string& field, double time) {
    if (!(time / s.dt <= kMaxSteps))
      throw SceneError(s.file + ": " + field + " = " + show(time) + ": " + show(time / s.dt) + " steps of dt = " + show(s.dt) +
                       " s, more than the limit of " + limit_text(kMaxSteps) + " (docs/scene.md, Limits)");
  };
  steps_limit("end.time", s.end_time);
  steps_limit("output.checkpoint_every", s.checkpoint_every);
  steps_limit("output.thermo_interval", s.thermo_interval);
  steps_limit("output.snapshot_interval", s.snapshot_interval);
  if (s.discharge.enabled) {
    steps_limit("discharge.time", s.discharge.time);
    steps_limit("discharge.series_interval", s.discharge.series_interval);
    steps_limit("discharge.peak_window", s.discharge.peak_window);
  }
  if (!s.start_from.empty()) {
    const std::string problem = regular_file_problem(s.start_from, 1e18);
    if (!problem.empty()) throw SceneError(s.file + ": start.from = \"" + s.start_from + "\": " + problem);
  }
}

}  // namespace

SceneSpec load_scene(const std::string& path, const SceneOverrides& ov) {
  toml::table root_table = parse_scene_file(path);
  for (const std::string& a : ov.sets) apply_assignment(root_table, a);
  return load_scene_table(root_table, path, ov);
}

SceneSpec load_scene_table(const toml::table& root_table, const std::string& file, const SceneOverrides& ov) {
  SceneSpec s;
  s.file = file;
  s.sets = ov.sets;
  s.max_discs = ov.max_discs > 0 ? ov.max_discs : kMaxDiscs;
  check_scene_keys(root_table, s.file);  // a misspelt key is named before a missing one
  Tab root(root_table, "", s.file);
  read_run_tables(s, root);
  read_materials(s, root);
  read_pairs(s, root);
  read_shear_tables(s, root_table);  // [shear_box] (adds its walls), [shear], [clusters]
  for (const char* k : {"shear_box", "shear", "clusters"}) root.node(k);
  read_walls(s, root);
  read_fill(s, root);
  finish_shear_tables(s);  // the plate above the discs; cluster indices
  read_end_and_neighbor(s, root);
  read_start(s, root);
  read_discharge(s, root);
  read_output(s, root);
  root.finish();
  check_pairs_complete(s);
  apply_overrides(s, ov);
  check_initial_discs(s);
  return s;
}

namespace {
// Everything but the contact lists (World::init).
StabilityReport set_up_world(const SceneSpec& s, World& w) {
  w = World{};
  w.n_materials = static_cast<int>(s.material_names.size());
  w.props = s.props;
  w.options = s.contact;
  w.scheme = s.scheme;
  w.rotation_angle = s.rotation_angle;
  w.dt = s.dt;
  w.threads = s.threads;
  w.gx = s.gx;
  w.gy = s.gy;
  w.geometry = s.geometry;
  w.geometry.link_points();
  w.discs.reserve(s.discs.size());
  for (const auto& d : s.discs) {
    w.discs.add(d.x, d.y, d.r, s.density[d.material], d.material);
    w.discs.vx.back() = d.vx;
    w.discs.vy.back() = d.vy;
    w.discs.omega.back() = d.omega;
  }
  build_shear_world(s, w);  // bonds, rotating walls, plate (paper 2); nothing for other scenes
  for (std::size_t k = 0; k < w.geometry.walls.size(); ++k) {  // walls[].velocity
    const Wall& wl = w.geometry.walls[k];
    if (!wl.moves()) continue;
    if (w.moving.motion.empty()) w.moving.motion.assign(w.geometry.obstacle_count(), ObstacleMotion{});
    TranslatingWall q;
    q.wall = static_cast<int>(k);
    q.vx = wl.move_vx; q.vy = wl.move_vy;
    q.t_from = wl.move_from; q.t_until = wl.move_until;
    q.ax0 = wl.ax; q.ay0 = wl.ay; q.bx0 = wl.bx; q.by0 = wl.by;
    w.moving.translating.push_back(q);
  }
  w.neighbors.skin = s.skin;
  w.neighbors.min_cell = s.cell;
  // The shear phase keeps each disc's row by index (ShearPhase::row_): its discs keep their order.
  w.disc_order = s.shear_box.enabled ? DiscOrder::off : s.disc_order;
  const StabilityReport rep = stability_report(w, s.material_names, default_length(s.units, kClusterTouch));
  if (s.dt > rep.dt_bound && !s.force_dt) {
    std::ostringstream os;
    os.precision(4);
    os << s.file << ": integrator.dt = " << s.dt << ": above the stability bound " << rep.dt_bound << " s of "
       << to_string(s.scheme) << " (set by " << rep.limited_by
       << "); set integrator.force_dt = true (or --force-dt) to run it anyway";
    throw SceneError(os.str());
  }
  return rep;
}
}  // namespace

StabilityReport build_world(const SceneSpec& s, World& w) {
  StabilityReport rep = set_up_world(s, w);
  w.init();
  return rep;
}

StabilityReport build_world_releasing_discs(SceneSpec& s, World& w) {
  StabilityReport rep = set_up_world(s, w);
  std::vector<DiscInit>().swap(s.discs);
  w.init();
  release_free_heap();  // the setup's temporaries: the scene's parse, the fill's file, the first build's scratch
  return rep;
}

}  // namespace dem
