#include "io/outputs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "io/vtu.hpp"
#include "io/opening_positions.hpp"

namespace dem {

using json = nlohmann::ordered_json;

namespace {

Digits17 fmt(double v) { return digits17(v); }

json pair_json(const PairReport& r) {
  return json{{"name", r.name},
              {"kind", r.disc_disc ? "disc-disc" : "disc-obstacle"},
              {"kn", r.p.kn}, {"ks", r.p.ks}, {"eta_n", r.p.eta_n}, {"eta_s", r.p.eta_s}, {"mu", r.p.mu},
              {"m_eff", r.m_eff}, {"m_t", r.m_t},
              {"omega0", r.omega0}, {"zeta_n", r.zeta_n},
              {"t_contact", finite_or_null(r.t_contact)}, {"restitution", r.restitution},
              {"omega_t", r.omega_t}, {"zeta_t", r.zeta_t},
              {"dt_bound_normal", finite_or_null(r.dt_normal)}, {"dt_bound_tangential", finite_or_null(r.dt_tangential)},
              {"dt_bound_eq26", r.dt_eq26}, {"dt_bound_eq21", r.dt_eq21},
              {"dt_bound_rotation_z4", finite_or_null(r.dt_rot_z4)}, {"dt_bound_rotation_z6", finite_or_null(r.dt_rot_z6)}};
}

}  // namespace


namespace {

// The k-th index of a list that `keep` accepts, asked for in increasing k: a k below the last one
// asked starts the scan again from the list's start. The contact files read their contacts in
// order, once a section of the VTU, so no list of the accepted indices is kept (at the end of a
// dense 1M-disc run such lists, 8 bytes a touching pair, set the run's peak memory).
class NthKept {
 public:
  template <class Keep>
  std::size_t find(std::size_t k, Keep&& keep) {  // k below the number of accepted entries
    if (!started_ || k < k_) {
      started_ = true;
      k_ = 0;
      at_ = 0;
      while (!keep(at_)) ++at_;
    }
    for (; k_ < k; ++k_)
      for (++at_; !keep(at_);) ++at_;
    return at_;
  }

 private:
  bool started_ = false;
  std::size_t k_ = 0, at_ = 0;
};

// The contacts of the contact files, in this order: the touching disc-disc pairs (list order),
// the bonds between distinct places, the touching obstacle contacts. Counted first, then read in
// order. Every contact is written where its forces were computed: eqs. (18) and (19) compute the
// forces and then move the discs in the same pass, so their discs are taken back by the step's
// increment (World::increments); Verlet computes the forces after its move.
class ContactRows {
 public:
  explicit ContactRows(const World& w)
      : w_(w), d_(w.discs), moved_after_forces_(!verlet_family(w.scheme) && w.steps > 0), inc_(w.increments()),
        recorded_(w.pair_forces_current()), nw_(static_cast<int>(w.geometry.walls.size())) {
    for (std::size_t p = 0; p < w.neighbors.pairs.size(); ++p) np_ += touching(p);
    for (std::size_t p = 0; p < w.bonds.size(); ++p) nb_ += bonded(p);
    for (std::size_t p = 0; p < w.neighbors.walls.size(); ++p) nwc_ += wall_touching(p);
  }
  std::size_t size() const { return np_ + nb_ + nwc_; }
  // The contacts each disc has (by array index): its touching pairs, bonds and obstacles.
  std::vector<int> per_disc() const {
    std::vector<int> n(d_.size(), 0);
    for (std::size_t p = 0; p < w_.neighbors.pairs.size(); ++p)
      if (touching(p)) ++n[w_.neighbors.pairs[p].i], ++n[w_.neighbors.pairs[p].j];
    for (std::size_t p = 0; p < w_.bonds.size(); ++p)
      if (bonded(p)) ++n[w_.bonds[p].i], ++n[w_.bonds[p].j];
    for (std::size_t p = 0; p < w_.neighbors.walls.size(); ++p)
      if (wall_touching(p)) ++n[w_.neighbors.walls[p].i];
    return n;
  }

  // Contact c of the VTU: its forces, its disc i and its other end (disc j, or the obstacle point).
  struct Entry {
    double en, es, fn, fs;
    int kind;  // 0 disc-disc, 1 disc-wall, 2 disc-point, 3 bond
    int i, j;  // j < 0: the other end is (px, py)
    double px, py;
  };
  Entry entry(std::size_t c) {
    if (c < np_) {
      const std::size_t p = pair_at_.find(c, [this](std::size_t q) { return touching(q); });
      const PairContact& q = w_.neighbors.pairs[p];
      double fn, fs;
      totals(p, rec_at_, fn, fs);
      return {q.en, q.es, fn, fs, 0, q.i, q.j, 0, 0};
    }
    if (c < np_ + nb_) {
      const Bond& q = w_.bonds[bond_at_.find(c - np_, [this](std::size_t b) { return bonded(b); })];
      return {q.en, q.es, q.fn, q.fs, 3, q.i, q.j, 0, 0};
    }
    const WallContact& q = w_.neighbors.walls[wall_at_.find(c - np_ - nb_, [this](std::size_t a) { return wall_touching(a); })];
    return {q.en, q.es, q.fn, q.fs, q.k < nw_ ? 1 : 2, q.i, -1, q.px, q.py};
  }
  void point(std::size_t k, double& x, double& y) {  // point k: end k % 2 of contact k / 2
    const Entry e = entry(k / 2);
    const int i = k % 2 ? e.j : e.i;
    x = i >= 0 ? px(i) : e.px;
    y = i >= 0 ? py(i) : e.py;
  }

  // The CSV's rows in the lists' order: the discs are in the user's order.
  void write_list_order(std::ostream& o) const {
    PairTotals::Cursor r;
    for (std::size_t p = 0; p < w_.neighbors.pairs.size(); ++p) {
      if (!touching(p)) continue;
      double fn, fs;
      totals(p, r, fn, fs);
      write_pair(o, p, fn, fs);
    }
    for (std::size_t p = 0; p < w_.bonds.size(); ++p)
      if (bonded(p)) write_bond(o, p);
    for (std::size_t p = 0; p < w_.neighbors.walls.size(); ++p)
      if (wall_touching(p)) write_wall(o, p);
  }
  void write_id_order(std::ostream& o) const;

 private:
  double px(int i) const { return moved_after_forces_ ? d_.x[i] - inc_.x[i] * inc_.factor : d_.x[i]; }
  double py(int i) const { return moved_after_forces_ ? d_.y[i] - inc_.y[i] * inc_.factor : d_.y[i]; }
  double dist(int i, int j) const { return std::hypot(px(j) - px(i), py(j) - py(i)); }
  bool touching(std::size_t p) const {
    const PairContact& c = w_.neighbors.pairs[p];
    const double R = dist(c.i, c.j);
    return R <= d_.r(c.i) + d_.r(c.j) && R != 0;
  }
  bool bonded(std::size_t p) const { return dist(w_.bonds[p].i, w_.bonds[p].j) != 0; }
  bool wall_touching(std::size_t p) const { return w_.neighbors.walls[p].touching; }
  // A pair's totals: its entry in the recorded totals of this step, found by a cursor walking
  // them beside the pairs (PairTotals::at); (0, 0) for a pair that pass found apart, NaN when this
  // step's forces were not recorded (the run loops record them).
  void totals(std::size_t p, PairTotals::Cursor& r, double& fn, double& fs) const {
    const PairTotals::Force* f = recorded_ ? w_.pair_totals.at(w_.neighbors.pairs, p, r) : nullptr;
    fn = !recorded_ ? NAN : f ? f->fn : 0.0;
    fs = !recorded_ ? NAN : f ? f->fs : 0.0;
  }
  void write_pair(std::ostream& o, std::size_t p, double fn, double fs) const {
    const Discs& d = d_;
    const PairContact& c = w_.neighbors.pairs[p];
    const bool flip = d.id_at(c.i) > d.id_at(c.j);  // a pair seen from its other disc: the normal reversed
    const int i = flip ? c.j : c.i, j = flip ? c.i : c.j;
    const double dx = px(j) - px(i), dy = py(j) - py(i);
    const double R = std::hypot(dx, dy);
    const double nx = dx / R, ny = dy / R, ov = d.r(i) + d.r(j) - R;
    const double cx = px(i) + nx * (d.r(i) - 0.5 * ov), cy = py(i) + ny * (d.r(i) - 0.5 * ov);
    o << "dd," << d.id_at(i) << ',' << d.id_at(j) << ',' << fmt(cx) << ',' << fmt(cy) << ',' << fmt(nx) << ','
      << fmt(ny) << ',' << fmt(c.en) << ',' << fmt(c.es) << ',' << fmt(fn) << ',' << fmt(fs) << '\n';
  }
  void write_bond(std::ostream& o, std::size_t p) const {  // cluster bonds (paper 2), at their bond point; e_n < 0 is tension
    const Discs& d = d_;
    const Bond& c = w_.bonds[p];
    const bool flip = d.id_at(c.i) > d.id_at(c.j);
    const int i = flip ? c.j : c.i, j = flip ? c.i : c.j;
    const double ai = flip ? c.aj : c.ai, aj = flip ? c.ai : c.aj;
    const double dx = px(j) - px(i), dy = py(j) - py(i);
    const double R = std::hypot(dx, dy);
    const double nx = dx / R, ny = dy / R, at = ai / (ai + aj) * R;
    o << "db," << d.id_at(i) << ',' << d.id_at(j) << ',' << fmt(px(i) + nx * at) << ',' << fmt(py(i) + ny * at)
      << ',' << fmt(nx) << ',' << fmt(ny) << ',' << fmt(c.en) << ',' << fmt(c.es) << ',' << fmt(c.fn) << ','
      << fmt(c.fs) << '\n';
  }
  void write_wall(std::ostream& o, std::size_t p) const {
    const WallContact& c = w_.neighbors.walls[p];
    const bool is_wall = c.k < nw_;
    const std::string& name = is_wall ? w_.geometry.walls[c.k].name : w_.geometry.points[c.k - nw_].name;
    o << (is_wall ? "dw," : "dp,") << d_.id_at(c.i) << ',' << name << ',' << fmt(c.px) << ',' << fmt(c.py) << ','
      << fmt(c.nx) << ',' << fmt(c.ny) << ',' << fmt(c.en) << ',' << fmt(c.es) << ',' << fmt(c.fn) << ','
      << fmt(c.fs) << '\n';
  }

  const World& w_;
  const Discs& d_;
  const bool moved_after_forces_;
  const World::Increments inc_;
  const bool recorded_;
  const int nw_;
  std::size_t np_ = 0, nb_ = 0, nwc_ = 0;
  NthKept pair_at_, bond_at_, wall_at_;
  PairTotals::Cursor rec_at_;  // the record cursor (a section read from its start again restarts it)
};

// Discs in cell order (World::resort_discs): the rows in the user's order, as the lists would
// have them over discs in id order: pairs by (id_i, id_j) with id_i < id_j, then bonds, then
// obstacle contacts by (id, obstacle). Sorted as packed keys (group, a, b: 2 + 31 + 31 bits)
// with the row's source, 16 B a row, and the pairs' totals read in list order (16 B a pair):
// the rows' text gathered and sorted was 35 MB at 100k discs, some 350 MB at 1M.
void ContactRows::write_id_order(std::ostream& o) const {
  const Discs& d = d_;
  struct Row {
    std::uint64_t key;
    std::uint32_t at;  // pairs: the index in `pair_rows`; bonds and walls: their list index
  };
  const auto key = [](std::uint64_t group, long long a, long long b) {
    return group << 62 | static_cast<std::uint64_t>(a) << 31 | static_cast<std::uint64_t>(b);
  };
  struct PairRow {
    std::size_t p;
    double fn, fs;
  };
  std::vector<PairRow> pair_rows;
  pair_rows.reserve(np_);
  std::vector<Row> rows;
  rows.reserve(size());
  PairTotals::Cursor r;
  for (std::size_t p = 0; p < w_.neighbors.pairs.size(); ++p) {
    if (!touching(p)) continue;
    const PairContact& c = w_.neighbors.pairs[p];
    PairRow pr{p, 0, 0};
    totals(p, r, pr.fn, pr.fs);
    const long long a = d.id_at(c.i), b = d.id_at(c.j);
    rows.push_back({key(0, std::min(a, b), std::max(a, b)), static_cast<std::uint32_t>(pair_rows.size())});
    pair_rows.push_back(pr);
  }
  for (std::size_t p = 0; p < w_.bonds.size(); ++p) {
    if (!bonded(p)) continue;
    const long long a = d.id_at(w_.bonds[p].i), b = d.id_at(w_.bonds[p].j);
    rows.push_back({key(1, std::min(a, b), std::max(a, b)), static_cast<std::uint32_t>(p)});
  }
  for (std::size_t p = 0; p < w_.neighbors.walls.size(); ++p)
    if (wall_touching(p))
      rows.push_back({key(2, d.id_at(w_.neighbors.walls[p].i), w_.neighbors.walls[p].k), static_cast<std::uint32_t>(p)});
  std::sort(rows.begin(), rows.end(), [](const Row& x, const Row& y) { return x.key < y.key; });
  for (const Row& row : rows) {
    const std::uint64_t group = row.key >> 62;
    if (group == 0) write_pair(o, pair_rows[row.at].p, pair_rows[row.at].fn, pair_rows[row.at].fs);
    else if (group == 1) write_bond(o, row.at);
    else write_wall(o, row.at);
  }
}

}  // namespace

void write_contact_files(const std::string& dir, const std::string& stem, const World& w, bool binary, bool vtu) {
  ContactRows contacts(w);
  std::ofstream o;  // NAME.csv.tmp, renamed when complete
  const std::string csv = dir + "/" + stem + ".csv";
  o.open(csv + ".tmp", std::ios::binary);
  o << "kind,i,j,x,y,nx,ny,e_n,e_s,f_n,f_s\n";
  if (w.discs.by_id().empty()) contacts.write_list_order(o);
  else contacts.write_id_order(o);
  o.close();
  if (!o) throw std::runtime_error("cannot write " + csv + ".tmp");
  std::filesystem::rename(csv + ".tmp", csv);
  if (!vtu) return;
  VtuGrid g;
  g.np = 2 * contacts.size();
  g.point = [&](std::size_t k, double& x, double& y) { contacts.point(k, x, y); };
  g.points_per_cell = 2;
  g.vtk_type = 3;  // VTK_LINE
  g.scalars = {{"f_n", [&](std::size_t c) { return contacts.entry(c).fn; }},
               {"f_s", [&](std::size_t c) { return contacts.entry(c).fs; }},
               {"e_n", [&](std::size_t c) { return contacts.entry(c).en; }},
               {"e_s", [&](std::size_t c) { return contacts.entry(c).es; }}};
  g.ints = {{"kind", [&](std::size_t c) { return static_cast<long long>(contacts.entry(c).kind); }}};
  g.cell_data = true;
  write_stream_atomic(dir + "/" + stem + ".vtu", [&](std::ostream& out) { write_vtu(out, g, binary); });
}

void write_disc_files(const std::string& dir, const std::string& stem, const SceneSpec& spec, const Discs& d,
                      const OpeningPositions* at_open, const World* world) {
  const bool disp = at_open != nullptr;
  // Row k is the disc of the k-th smallest id: the user's order, whatever the arrays' (cell order
  // after a re-sort, World::resort_discs).
  const std::vector<int> by_id = d.by_id();
  const auto disc = [&](std::size_t k) { return by_id.empty() ? k : static_cast<std::size_t>(by_id[k]); };
  // Read in id order, the discs' order: a block of positions at a time (opening_positions.hpp).
  std::optional<OpeningPositions::Reader> open_at;
  if (disp) open_at.emplace(*at_open);
  const auto displacement = [&](std::size_t i, double& dx, double& dy) {
    double x0, y0;
    open_at->at(d.id_at(i), x0, y0);
    dx = d.x[i] - x0;
    dy = d.y[i] - y0;
  };
  std::ofstream o;  // NAME.csv.tmp, renamed when complete
  const std::string csv = dir + "/" + stem + ".csv";
  o.open(csv + ".tmp", std::ios::binary);
  const bool angle = !d.phi.empty();  // output.rotation_angle
  o << "id,x,y,r,vx,vy,omega,material" << (disp ? ",dx,dy" : "") << (angle ? ",phi" : "") << "\n";
  for (std::size_t k = 0; k < d.size(); ++k) {
    const std::size_t i = disc(k);
    o << d.id_at(i) << ',' << fmt(d.x[i]) << ',' << fmt(d.y[i]) << ',' << fmt(d.r(i)) << ',' << fmt(d.vx[i]) << ','
      << fmt(d.vy[i]) << ',' << fmt(d.omega[i]) << ',' << spec.material_names[d.material(i)];
    if (disp) {
      double dx, dy;
      displacement(i, dx, dy);
      o << ',' << fmt(dx) << ',' << fmt(dy);
    }
    if (angle) o << ',' << fmt(d.phi[i]);
    o << '\n';
  }
  o.close();
  if (!o) throw std::runtime_error("cannot write " + csv + ".tmp");
  std::filesystem::rename(csv + ".tmp", csv);
  if (!spec.vtu_files()) return;
  std::vector<VtuVector> vec;
  vec.push_back({"velocity", [&](std::size_t k, double& vx, double& vy) { vx = d.vx[disc(k)]; vy = d.vy[disc(k)]; }});
  // The resultant of eq. (15) on each disc (gravity included) and its moment.
  vec.push_back({"force", [&](std::size_t k, double& fx, double& fy) { fx = d.fx[disc(k)]; fy = d.fy[disc(k)]; }});
  if (disp) vec.push_back({"displacement", [&](std::size_t k, double& dx, double& dy) { displacement(disc(k), dx, dy); }});
  std::vector<VtuColumn> scalars = {{"radius", [&](std::size_t k) { return d.r(disc(k)); }},
                                 {"omega", [&](std::size_t k) { return d.omega[disc(k)]; }},
                                 {"torque", [&](std::size_t k) { return d.torque[disc(k)]; }}};
  if (angle) scalars.push_back({"phi", [&](std::size_t k) { return d.phi[disc(k)]; }});
  VtuGrid g;
  g.np = d.size();
  g.point = [&](std::size_t k, double& x, double& y) { x = d.x[disc(k)]; y = d.y[disc(k)]; };
  g.scalars = std::move(scalars);
  g.vectors = std::move(vec);
  g.ints = {{"id", [&](std::size_t k) { return static_cast<long long>(d.id_at(disc(k))); }},
            {"material", [&](std::size_t k) { return static_cast<long long>(d.material(disc(k))); }}};
  std::vector<int> contacts;  // of the world's discs only (not of a last good state)
  if (world && &world->discs == &d) {
    contacts = ContactRows(*world).per_disc();
    g.ints.push_back({"contacts", [&](std::size_t k) { return static_cast<long long>(contacts[disc(k)]); }});
  }
  write_stream_atomic(dir + "/" + stem + ".vtu", [&](std::ostream& out) { write_vtu(out, g, spec.vtu_binary(d.size())); });
}

json stability_json(const StabilityReport& stab, Units units) {
  return {{"dt_bound", stab.dt_bound}, {"limited_by", stab.limited_by},
          {"dt_single_contact", stab.dt_single},
          {"dt_rotation_z4", finite_or_null(stab.dt_rot_z4)},
          {"dt_rotation_z6", finite_or_null(stab.dt_rot_z6)},
          {"dt_clusters", finite_or_null(stab.clusters.dt)},
          {"cluster_shapes", stab.clusters.shapes},
          {"clusters_not_examined", stab.clusters.skipped},
          {"note", std::string("bounds from the spectral radius of this scheme's step on one damped degree of freedom: "
                   "a single contact (normal, sticking shear), and a disc's rotation held by 4 or 6 "
                   "sticking contacts (disc-disc or disc-wall constants); with bonded clusters, on each "
                   "distinct cluster of at most 10 discs (its discs, bonds and the contacts to neighbours "
                   "within 0.01 ") + unit_names(units).length + ", those held fixed, every contact sticking); "
                   "dt_bound = min(single contact, rotation on 4, clusters) is enforced"}};
}

void write_outputs(const std::string& dir, const SceneSpec& spec, const World& w, const Loads& loads,
                   const RunSummary& res, const StabilityReport& stab, json* extra) {
  w.require_velocities("write_outputs");
  const bool unstable = res.unstable;
  // An unstable run writes its discs as they were in the last good state (a discharge may have
  // removed some since); wall loads and the summary's counters are those of the stop.
  const Discs& d = unstable && res.good ? *res.good : w.discs;
  const std::vector<WallLoad>& walls = loads.walls;
  const std::vector<PointLoad>& points = loads.points;
  const double g = std::hypot(w.gx, w.gy);
  const double ghx = w.gx / g, ghy = w.gy / g;
  double weight = 0;
  for (std::size_t i = 0; i < d.size(); ++i) weight += d.mass(i) * g;
  const double top = w.geometry.max_y();

  json js;
  js["engine"] = std::string("dem ") + DEM_VERSION;
  js["engine_version"] = DEM_VERSION;
  js["build_id"] = DEM_BUILD_ID;
  if (!res.command.empty()) js["command"] = res.command;
  js["scene"] = {{"name", spec.name}, {"file", spec.file}, {"description", spec.description}, {"fill", spec.fill_summary}};
  js["status"] = res.status;
  if (unstable) js["reason"] = res.reason;
  js["options"] = {{"scheme", to_string(w.scheme)}, {"dt", w.dt}, {"dt_forced", spec.force_dt}, {"threads", w.threads},
                   {"normal_spring", to_string(w.options.normal_spring)}, {"no_tension", to_string(w.options.no_tension)},
                   {"friction_cap", to_string(w.options.friction_cap)}, {"lever_arm", to_string(w.options.lever_arm)},
                   {"gravity", {w.gx, w.gy}}, {"units", to_string(spec.units)},
                   {"skin", w.neighbors.skin}, {"cell", w.neighbors.cell_size()}, {"profile_bin", spec.profile_bin},
                   {"disc_order", to_string(w.disc_order)}};
  js["n_discs"] = d.size();
  js["steps"] = w.steps;
  js["time"] = on_step_grid(w.time, w.dt);
  js["wall_time_s"] = res.wall_seconds;
  js["particle_steps"] = w.particle_steps;
  js["particle_steps_per_s"] = res.wall_seconds > 0 ? w.particle_steps / res.wall_seconds : 0.0;
  js["neighbor_rebuilds"] = w.neighbors.rebuilds;
  js["neighbor_patches"] = w.neighbors.patches;
  js["disc_resorts"] = w.resorts;  // the discs put in cell order (integrator.disc_order)
  js["rest"] = {{"reached", res.rest_reached}, {"time", res.rest_reached ? json(on_step_grid(res.rest_time, w.dt)) : json(nullptr)},
                {"criterion", "mean over discs of |du| and of |dv| per step < rest_factor * g * dt^2 (paper note 3)"},
                {"rest_factor", spec.rest_factor}, {"threshold", res.rest_threshold},
                {"mean_abs_du", res.mean_abs_du}, {"mean_abs_dv", res.mean_abs_dv}};
  js["weight"] = weight;
  js["disc_weight"] = d.size() == 0 ? 0.0 : d.mass(0) * g;
  js["width"] = w.geometry.max_x() - w.geometry.min_x();
  js["height"] = top - w.geometry.min_y();
  json jw = json::array();
  double vertical = 0;
  for (std::size_t k = 0; k < walls.size(); ++k) {
    const WallLoad& L = walls[k];
    const Wall& wl = w.geometry.walls[k];
    vertical += L.fx * ghx + L.fy * ghy;
    json prof;
    std::vector<double> slo, shi, dm, xm, ym;
    for (std::size_t b = 0; b < L.bin_normal.size(); ++b) {
      const double lo = b * L.bin, hi = std::min(L.length, (b + 1) * L.bin), mid = 0.5 * (lo + hi);
      const double x = wl.ax + (wl.bx - wl.ax) * mid / L.length, y = wl.ay + (wl.by - wl.ay) * mid / L.length;
      slo.push_back(lo); shi.push_back(hi); xm.push_back(x); ym.push_back(y); dm.push_back(top - y);
    }
    prof = {{"s_lo", slo}, {"s_hi", shi}, {"depth_mid", dm}, {"x_mid", xm}, {"y_mid", ym},
            {"normal", L.bin_normal}, {"shear", L.bin_shear}, {"contacts", L.bin_contacts}};
    jw.push_back({{"name", L.name}, {"group", L.group}, {"from", {wl.ax, wl.ay}}, {"to", {wl.bx, wl.by}},
                  {"normal_total", L.normal}, {"shear_total", L.shear}, {"force", {L.fx, L.fy}},
                  {"contacts", L.contacts}, {"profile", prof}});
  }
  js["walls"] = jw;
  json jp = json::array();
  for (const PointLoad& P : points) {
    vertical += P.fx * ghx + P.fy * ghy;
    jp.push_back({{"name", P.name}, {"group", P.group}, {"at", {P.x, P.y}}, {"force", {P.fx, P.fy}}, {"contacts", P.contacts}});
  }
  js["points"] = jp;
  std::map<std::string, std::array<double, 4>> groups;
  for (const WallLoad& L : walls) {
    auto& G = groups[L.group];
    G[0] += L.normal; G[1] += L.shear; G[2] += L.fx; G[3] += L.fy;
  }
  for (const PointLoad& P : points) {
    auto& G = groups[P.group];
    G[2] += P.fx; G[3] += P.fy;
  }
  json jg = json::object();
  for (const auto& [name, G] : groups)
    jg[name] = {{"normal_total", G[0]}, {"shear_total", G[1]}, {"force", {G[2], G[3]}}};
  js["groups"] = jg;
  js["balance"] = {{"weight", weight}, {"walls_vertical", vertical},
                   {"residual_relative", weight > 0 ? std::abs(weight - vertical) / weight : 0.0},
                   {"note", "weight of all discs against the vertical load on walls and points; equal at rest"}};
  json jd = json::array();
  for (const auto& p : stab.pairs) jd.push_back(pair_json(p));
  js["derived"] = jd;
  js["stability"] = stability_json(stab, spec.units);

  // wall_profiles.csv
  {
    std::ostringstream o;
    o << "wall,group,bin,s_lo,s_hi,x_mid,y_mid,depth_mid,normal,shear,contacts\n";
    for (const auto& pw : jw) {
      const auto& p = pw["profile"];
      for (std::size_t b = 0; b < p["normal"].size(); ++b)
        o << pw["name"].get<std::string>() << ',' << pw["group"].get<std::string>() << ',' << b << ','
          << fmt(p["s_lo"][b]) << ',' << fmt(p["s_hi"][b]) << ',' << fmt(p["x_mid"][b]) << ',' << fmt(p["y_mid"][b])
          << ',' << fmt(p["depth_mid"][b]) << ',' << fmt(p["normal"][b]) << ',' << fmt(p["shear"][b]) << ','
          << p["contacts"][b].get<int>() << '\n';
    }
    write_file_atomic(dir + "/wall_profiles.csv", o.str());
  }
  if (extra)
    for (auto& [k, v] : extra->items()) js[k] = std::move(v);
  if (!unstable) write_contact_files(dir, "contacts", w, spec.vtu_binary(d.size()), spec.vtu_files());
  write_disc_files(dir, "discs", spec, d, nullptr, &w);
  if (spec.vtu_files()) write_walls_vtu(dir + "/walls.vtu", w.geometry, spec.vtu_binary(d.size()));
  // Serialised straight to the file (some 1.3 MB of text at a million discs, which a string
  // built first held twice over as it grew, at the run's peak): the bytes of js.dump(2).
  write_stream_atomic(dir + "/summary.json", [&](std::ostream& out) { out << std::setw(2) << js << '\n'; });
}

}  // namespace dem
