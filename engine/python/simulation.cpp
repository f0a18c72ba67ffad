// dem.Simulation: a scene's world, stepped, filled or run as `dem run` runs it, and read back as
// numpy arrays. The per-disc arrays the engine keeps flat (x, y, vx, vy, omega, fx, fy, torque)
// are read-only views of its memory; everything else is a copy (docs/python.md has the table).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <tuple>

#include "io/files.hpp"
#include "io/out_dir.hpp"
#include "io/outputs.hpp"
#include "io/run_log.hpp"
#include "io/state.hpp"
#include "measures/wall_loads.hpp"
#include "physics/world.hpp"
#include "run/scene_run.hpp"
#include "run/status.hpp"
#include "scene/scene.hpp"
#include "scene_object.hpp"

namespace py = pybind11;

namespace dem::python {

namespace {

class Simulation {
 public:
  explicit Simulation(const Scene& scene) : spec_(scene.spec) {
    stab_ = build_world(spec_, world_);
    if (!spec_.start_from.empty()) load_state(world_, spec_.start_from);
  }

  // n steps of the world as they are; the last records its pair forces (contacts()).
  void step(long n) {
    if (n < 0) throw py::value_error("step(n): n must be >= 0");
    for (long k = 0; k < n;) {
      const long chunk = std::min(n - k, 1000L);
      {
        py::gil_scoped_release free;
        for (long c = 0; c < chunk; ++c, ++k) {
          world_.record_pair_forces = k + 1 == n;
          world_.step();
        }
        world_.record_pair_forces = false;
      }
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C between chunks
    }
    status_ = Status::running;
  }

  // The fill alone (to rest or end.time), the scene's other phases not run.
  std::string fill() {
    {
      py::gil_scoped_release free;
      status_ = run_fill(spec_, world_, &rest_);
    }
    return to_string(status_);
  }

  // The scene's phases from its start, as `dem run SCENE --out DIR --quiet` runs them: its
  // outputs and run.log (the header, the phases' lines, the status line) written into out.
  std::string run(const std::filesystem::path& out_path, bool progress) {
    const std::string out = out_path.string();
    if (world_.steps != 0 && spec_.start_from.empty())
      throw std::runtime_error("run() runs a scene from its start: make a new Simulation");
    const int cleared = clear_run_outputs(out);  // a fresh run's folder, as dem run leaves it
    std::filesystem::create_directories(out);
    RunLog log(progress);
    log.add(run_header(spec_, world_, stab_));
    if (set_by_script_) log.say("  discs' start set from Python (set_positions, set_velocities, set_spins)\n");
    if (cleared > 0) log.say("  removed %d files of an earlier run from %s\n", cleared, out.c_str());
    SceneRun run(spec_, world_, out);
    run.log = &log;
    {
      py::gil_scoped_release free;
      status_ = run.run(progress, false);
    }
    nlohmann::ordered_json extra;
    const RunSummary summary = run.summary(extra);
    rest_ = run.fill.rest;
    write_outputs(out, spec_, world_, measure_loads(world_, spec_.profile_bin), summary, stab_, &extra);
    run.discard_kept();
    if (status_ == Status::unstable) log.say("  unstable: %s\n", summary.reason.c_str());
    log.say("  %s at t = %.4f s after %ld steps; fill rest %s; %.3g s wall\n", to_string(status_), world_.time,
            world_.steps, summary.rest_reached ? "reached" : "not reached", summary.wall_seconds);
    log.write(out, false);
    return to_string(status_);
  }

  // Sets one column of the discs' start (ids in order: the user's order) before the first step,
  // validated as a scene's fill is (finite, within the limits, no overlap, inside the walls), and
  // builds the world again from it; refused values leave the simulation as it was.
  void set_start(const char* what, const std::vector<py::array_t<double, py::array::c_style | py::array::forcecast>>& cols,
                 const std::vector<double DiscInit::*>& fields) {
    if (world_.steps != 0) throw py::value_error(std::string(what) + ": only before the first step (make a new Simulation)");
    if (!spec_.start_from.empty())
      throw py::value_error(std::string(what) + ": the scene starts from the state file " + spec_.start_from);
    SceneSpec s = spec_;
    for (std::size_t c = 0; c < fields.size(); ++c) {
      const auto a = cols[c].unchecked<1>();
      if (static_cast<std::size_t>(a.shape(0)) != s.discs.size())
        throw py::value_error(std::string(what) + ": " + std::to_string(a.shape(0)) + " values for " +
                              std::to_string(s.discs.size()) + " discs");
      for (std::size_t k = 0; k < s.discs.size(); ++k) s.discs[k].*fields[c] = a(k);
    }
    check_disc_values(s);
    check_initial_discs(s);
    World w;
    const StabilityReport stab = build_world(s, w);
    spec_ = std::move(s);
    world_ = std::move(w);
    stab_ = stab;
    status_ = Status::running;
    set_by_script_ = true;
  }

  // Columns of an (N, 2) array.
  static std::vector<py::array_t<double, py::array::c_style | py::array::forcecast>> columns(const char* what,
      const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
    if (a.ndim() != 2 || a.shape(1) != 2) throw py::value_error(std::string(what) + ": an (N, 2) array is needed");
    const auto v = a.unchecked<2>();
    py::array_t<double> x(a.shape(0)), y(a.shape(0));
    auto xm = x.mutable_unchecked<1>();
    auto ym = y.mutable_unchecked<1>();
    for (py::ssize_t k = 0; k < a.shape(0); ++k) { xm(k) = v(k, 0); ym(k) = v(k, 1); }
    return {x, y};
  }

  // The outputs of the world as it stands (after step or fill), as a run writes them.
  void write(const std::filesystem::path& out_path) {
    const std::string out = out_path.string();
    std::filesystem::create_directories(out);
    RunSummary s;
    s.status = to_string(status_);
    s.rest_reached = rest_.reached;
    s.rest_time = rest_.time;
    s.rest_threshold = rest_.threshold;
    s.mean_abs_du = rest_.mean_abs_du;
    s.mean_abs_dv = rest_.mean_abs_dv;
    write_outputs(out, spec_, world_, measure_loads(world_, spec_.profile_bin), s, stab_);
  }

  // A read-only view of a flat array, kept alive by this object. Steps may move the engine's
  // arrays (a discharge removes discs), so a view is read again after each step.
  // Discs in cell order (World::resort_discs) are listed in id order, the user's: a copy then.
  py::array_t<double> view(const std::vector<double>& v, const py::object& self) const {
    const std::vector<int> by_id = world_.discs.by_id();
    if (!by_id.empty()) {
      py::array_t<double> a = per_disc([&](std::size_t i) { return v[i]; }, by_id);
      py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
      return a;
    }
    py::array_t<double> a({static_cast<py::ssize_t>(v.size())}, {static_cast<py::ssize_t>(sizeof(double))}, v.data(), self);
    py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return a;
  }

  py::array_t<double> pairs_of(const std::vector<double>& a, const std::vector<double>& b) const {
    const std::vector<int> by_id = world_.discs.by_id();
    py::array_t<double> out({static_cast<py::ssize_t>(a.size()), py::ssize_t{2}});
    auto o = out.mutable_unchecked<2>();
    for (std::size_t k = 0; k < a.size(); ++k) {
      const std::size_t i = by_id.empty() ? k : static_cast<std::size_t>(by_id[k]);
      o(k, 0) = a[i];
      o(k, 1) = b[i];
    }
    return out;
  }

  // f(i) of each disc, in id order.
  template <class F>
  py::array_t<double> per_disc(F&& f) const {
    return per_disc(f, world_.discs.by_id());
  }
  template <class F>
  py::array_t<double> per_disc(F&& f, const std::vector<int>& by_id) const {
    py::array_t<double> out(static_cast<py::ssize_t>(world_.discs.size()));
    auto o = out.mutable_unchecked<1>();
    for (std::size_t k = 0; k < world_.discs.size(); ++k) o(k) = f(by_id.empty() ? k : static_cast<std::size_t>(by_id[k]));
    return out;
  }

  // The touching contacts as contacts.csv lists them (docs/outputs.md): disc-disc pairs in list
  // order, bonds, then disc-wall and disc-point contacts.
  py::dict contacts() const {
    const World& w = world_;
    const Discs& d = w.discs;
    const bool moved_after_forces = !verlet_family(w.scheme) && w.steps > 0;  // as the CSV
    const World::Increments inc = w.increments();
    const auto px = [&](int i) { return moved_after_forces ? d.x[i] - inc.x[i] * inc.factor : d.x[i]; };
    const auto py_ = [&](int i) { return moved_after_forces ? d.y[i] - inc.y[i] * inc.factor : d.y[i]; };
    struct Row {
      int kind, i, j;
      double en, es, fn, fs;
    };
    std::vector<Row> rows;
    const bool recorded = w.pair_forces_current();
    PairTotals::Cursor r;
    // Pairs by ids with id_i < id_j (discs in cell order, World::resort_discs: as contacts.csv).
    const auto ids = [&](int a, int b) { return std::make_pair(std::min(d.id_at(a), d.id_at(b)), std::max(d.id_at(a), d.id_at(b))); };
    for (std::size_t p = 0; p < w.neighbors.pairs.size(); ++p) {
      const PairContact& c = w.neighbors.pairs[p];
      const double R = std::hypot(px(c.j) - px(c.i), py_(c.j) - py_(c.i));
      if (!(R <= d.r(c.i) + d.r(c.j) && R != 0)) continue;
      const PairTotals::Force* f = recorded ? w.pair_totals.at(w.neighbors.pairs, p, r) : nullptr;
      const auto [a, b] = ids(c.i, c.j);
      rows.push_back({0, a, b, c.en, c.es, !recorded ? NAN : f ? f->fn : 0.0, !recorded ? NAN : f ? f->fs : 0.0});
    }
    for (const Bond& c : w.bonds) {
      if (std::hypot(px(c.j) - px(c.i), py_(c.j) - py_(c.i)) == 0) continue;
      const auto [a, b] = ids(c.i, c.j);
      rows.push_back({3, a, b, c.en, c.es, c.fn, c.fs});
    }
    const int nw = static_cast<int>(w.geometry.walls.size());
    for (const WallContact& c : w.neighbors.walls) {
      if (!c.touching) continue;
      rows.push_back({c.k < nw ? 1 : 2, d.id_at(c.i), c.k < nw ? c.k : c.k - nw, c.en, c.es, c.fn, c.fs});
    }
    if (!d.by_id().empty()) {  // the lists' order over ids: pairs, bonds, obstacle contacts (by id, obstacle)
      const auto group = [](const Row& q) { return q.kind == 0 ? 0 : q.kind == 3 ? 1 : 2; };
      const auto other = [&](const Row& q) { return q.kind == 2 ? q.j + nw : q.j; };
      std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) {
        return std::make_tuple(group(a), a.i, other(a)) < std::make_tuple(group(b), b.i, other(b));
      });
    }
    std::vector<int> kind, ci, cj;
    std::vector<double> en, es, fn, fs;
    for (const Row& q : rows) {
      kind.push_back(q.kind); ci.push_back(q.i); cj.push_back(q.j);
      en.push_back(q.en); es.push_back(q.es); fn.push_back(q.fn); fs.push_back(q.fs);
    }
    py::dict out;
    out["kind"] = py::array_t<int>(kind.size(), kind.data());
    out["i"] = py::array_t<int>(ci.size(), ci.data());
    out["j"] = py::array_t<int>(cj.size(), cj.data());
    out["e_n"] = py::array_t<double>(en.size(), en.data());
    out["e_s"] = py::array_t<double>(es.size(), es.data());
    out["f_n"] = py::array_t<double>(fn.size(), fn.data());
    out["f_s"] = py::array_t<double>(fs.size(), fs.data());
    return out;
  }

  // The forces of the discs on each wall and point (summary.json's walls and points).
  py::dict loads(bool points) const {
    std::vector<WallLoad> walls;
    std::vector<PointLoad> pts;
    measure_loads(world_, spec_.profile_bin, walls, pts);
    py::dict out;
    py::list names, groups;
    std::vector<double> fx, fy, normal, shear;
    std::vector<int> contacts;
    if (points) {
      for (const PointLoad& p : pts) {
        names.append(p.name); groups.append(p.group);
        fx.push_back(p.fx); fy.push_back(p.fy); contacts.push_back(p.contacts);
      }
    } else {
      for (const WallLoad& l : walls) {
        names.append(l.name); groups.append(l.group);
        fx.push_back(l.fx); fy.push_back(l.fy); normal.push_back(l.normal); shear.push_back(l.shear);
        contacts.push_back(l.contacts);
      }
      out["normal"] = py::array_t<double>(normal.size(), normal.data());
      out["shear"] = py::array_t<double>(shear.size(), shear.data());
    }
    out["name"] = names;
    out["group"] = groups;
    out["fx"] = py::array_t<double>(fx.size(), fx.data());
    out["fy"] = py::array_t<double>(fy.size(), fy.data());
    out["contacts"] = py::array_t<int>(contacts.size(), contacts.data());
    return out;
  }

  World world_;
  Status status_ = Status::running;
  Rest rest_;

 private:
  SceneSpec spec_;  // the world's scene (SceneRun and the outputs read it)
  StabilityReport stab_;
  bool set_by_script_ = false;  // the discs' start came from set_positions / set_velocities / set_spins
};

}  // namespace

void bind_simulation(py::module_& m) {
  using S = Simulation;
  auto flat = [](std::vector<double> Discs::*member) {
    return [member](py::object self) {
      const S& s = self.cast<const S&>();
      return s.view(s.world_.discs.*member, self);
    };
  };
  py::class_<S>(m, "Simulation", R"(A scene's world (built and checked as `dem run` builds it).

step(n) steps it; fill() runs the fill to rest or end.time; run(out) runs every phase of the scene
(fill, discharge, shear) and writes the outputs, as `dem run SCENE --out DIR --quiet`; write(out)
writes the outputs of the world as it stands. set_positions, set_velocities and set_spins set the discs'
start before the first step, validated as a scene's fill. x, y, vx, vy, omega, fx, fy, torque are read-only
views of the engine's arrays (no copy; read them again after stepping; read-only copies once the
engine has put the discs in cell order: every array lists the discs in id order); positions, velocities,
forces, radii, ids, contacts(), walls() and points() are copies.)")
      .def(py::init<const Scene&>(), py::arg("scene"))
      .def("step", &S::step, py::arg("n") = 1, "n time steps (the last one records the pair forces contacts() reads)")
      .def("fill", &S::fill, "The fill to rest (the paper's note 3) or end.time; returns the status ('rest', 'end_time', 'unstable', ...).")
      .def("run", &S::run, py::arg("out"), py::arg("progress") = false,
           "Every phase of the scene from its start, and its outputs written into out (created), as dem run does; returns the status.")
      .def("write", &S::write, py::arg("out"), "The outputs of the world as it stands into out (created), as a run writes them.")
      .def("set_positions", [](S& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
             s.set_start("set_positions", S::columns("set_positions", a), {&DiscInit::x, &DiscInit::y});
           }, py::arg("positions"),
           "Sets the discs' centres, an (N, 2) array in id order, before the first step; validated as a scene's fill "
           "(finite, no overlap beyond fill.max_initial_overlap, inside the walls): dem.SceneError names the disc.")
      .def("set_velocities", [](S& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
             s.set_start("set_velocities", S::columns("set_velocities", a), {&DiscInit::vx, &DiscInit::vy});
           }, py::arg("velocities"), "Sets the discs' velocities, an (N, 2) array in id order, before the first step.")
      .def("set_spins", [](S& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
             if (a.ndim() != 1) throw py::value_error("set_spins: an (N,) array is needed");
             s.set_start("set_spins", {a}, {&DiscInit::omega});
           }, py::arg("omega"), "Sets the discs' spins [1/s], an (N,) array in id order, before the first step.")
      .def_property_readonly("x", flat(&Discs::x))
      .def_property_readonly("y", flat(&Discs::y))
      .def_property_readonly("vx", flat(&Discs::vx))
      .def_property_readonly("vy", flat(&Discs::vy))
      .def_property_readonly("omega", flat(&Discs::omega), "spins [1/s], counter-clockwise")
      .def_property_readonly("fx", flat(&Discs::fx), "resultant force of eq. (15), gravity included")
      .def_property_readonly("fy", flat(&Discs::fy))
      .def_property_readonly("torque", flat(&Discs::torque))
      .def_property_readonly("positions", [](const S& s) { return s.pairs_of(s.world_.discs.x, s.world_.discs.y); }, "(N, 2) copy")
      .def_property_readonly("velocities", [](const S& s) { return s.pairs_of(s.world_.discs.vx, s.world_.discs.vy); }, "(N, 2) copy")
      .def_property_readonly("forces", [](const S& s) { return s.pairs_of(s.world_.discs.fx, s.world_.discs.fy); }, "(N, 2) copy")
      .def_property_readonly("radii", [](const S& s) { return s.per_disc([&](std::size_t i) { return s.world_.discs.r(i); }); },
                             "copy (the engine keeps radii per kind of disc)")
      .def_property_readonly("masses", [](const S& s) { return s.per_disc([&](std::size_t i) { return s.world_.discs.mass(i); }); },
                             "rho pi r^2 [g per cm of thickness]; copy")
      .def_property_readonly("ids", [](const S& s) {
        const std::vector<int> by_id = s.world_.discs.by_id();
        py::array_t<int> out(static_cast<py::ssize_t>(s.world_.discs.size()));
        auto o = out.mutable_unchecked<1>();
        for (std::size_t k = 0; k < s.world_.discs.size(); ++k)
          o(k) = s.world_.discs.id_at(by_id.empty() ? k : static_cast<std::size_t>(by_id[k]));
        return out;
      }, "the discs' ids (a disc keeps its id when others are removed); copy")
      .def("contacts", &S::contacts,
           "The touching contacts as contacts.csv lists them: dict of arrays kind (0 disc-disc, 1 disc-wall, 2 "
           "disc-point, 3 bond), i (disc id), j (disc id, wall or point index), e_n, e_s, f_n, f_s (disc-disc f_n, f_s "
           "are NaN unless the last step recorded them); copies.")
      .def("walls", [](const S& s) { return s.loads(false); },
           "The forces of the discs on each wall: dict of name, group, fx, fy, normal, shear, contacts; copies.")
      .def("points", [](const S& s) { return s.loads(true); }, "The forces on each point (slit ends): name, group, fx, fy, contacts.")
      .def("kinetic_energy", [](const S& s) { return s.world_.kinetic_energy(); })
      .def_property_readonly("time", [](const S& s) { return on_step_grid(s.world_.time, s.world_.dt); },
                             "simulated time [s], as summary.json gives it (on the step grid)")
      .def_property_readonly("steps", [](const S& s) { return s.world_.steps; })
      .def_property_readonly("dt", [](const S& s) { return s.world_.dt; })
      .def_property_readonly("n_discs", [](const S& s) { return s.world_.discs.size(); })
      .def_property_readonly("status", [](const S& s) { return std::string(to_string(s.status_)); })
      .def_property_readonly("rest_reached", [](const S& s) { return s.rest_.reached; })
      .def_property_readonly("rest_time", [](const S& s) { return s.rest_.reached ? py::object(py::float_(s.rest_.time)) : py::object(py::none()); });
}

}  // namespace dem::python
