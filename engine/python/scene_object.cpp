#include "scene_object.hpp"

#include <pybind11/stl.h>

#include <memory>
#include <sstream>

#include "scene/resolve.hpp"
#include "scene/scene_set.hpp"
#include "scene/scene_table.hpp"

namespace py = pybind11;

namespace dem::python {

namespace {

// A Python value as a TOML node; `key` names it in errors.
std::unique_ptr<toml::node> to_toml(const py::handle& v, const std::string& key);

toml::table table_of(const py::dict& d, const std::string& key) {
  toml::table t;
  for (const auto& [k, v] : d) {
    if (!py::isinstance<py::str>(k))
      throw SceneError((key.empty() ? "" : key + ": ") + "a table key must be a string, not " + std::string(py::repr(k)));
    const std::string name = k.cast<std::string>();
    t.insert(name, *to_toml(v, key.empty() ? name : key + "." + name));
  }
  return t;
}

std::unique_ptr<toml::node> to_toml(const py::handle& v, const std::string& key) {
  if (py::isinstance<py::bool_>(v)) return std::make_unique<toml::value<bool>>(v.cast<bool>());
  if (py::isinstance<py::str>(v)) return std::make_unique<toml::value<std::string>>(v.cast<std::string>());
  if (py::isinstance<py::dict>(v)) return std::make_unique<toml::table>(table_of(v.cast<py::dict>(), key));
  if (py::isinstance<py::int_>(v) || (py::hasattr(v, "__index__") && !py::isinstance<py::float_>(v)))
    return std::make_unique<toml::value<int64_t>>(py::int_(v.attr("__index__")()).cast<int64_t>());
  if (py::isinstance<py::float_>(v) || py::hasattr(v, "__float__")) return std::make_unique<toml::value<double>>(v.cast<double>());
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    toml::array a;
    std::size_t k = 0;
    for (const auto& e : v) a.push_back(*to_toml(e, key + "." + std::to_string(k++)));
    return std::make_unique<toml::array>(std::move(a));
  }
  throw SceneError(key + " = " + std::string(py::repr(v)) + ": not a scene value (a number, bool, string, list or dict)");
}

py::object to_python(const toml::node& n) {
  if (auto t = n.as_table()) {
    py::dict d;
    for (const auto& [k, v] : *t) d[py::str(std::string(k.str()))] = to_python(v);
    return std::move(d);
  }
  if (auto a = n.as_array()) {
    py::list l;
    for (const auto& e : *a) l.append(to_python(e));
    return std::move(l);
  }
  if (auto v = n.as_string()) return py::str(v->get());
  if (auto v = n.as_integer()) return py::int_(v->get());
  if (auto v = n.as_floating_point()) return py::float_(v->get());
  if (auto v = n.as_boolean()) return py::bool_(v->get());
  std::ostringstream os;  // dates and times: as written
  n.visit([&](auto&& x) { os << x; });
  return py::str(os.str());
}

std::string path_of(const py::handle& p) { return py::str(py::module_::import("os").attr("fspath")(p)); }

}  // namespace

Scene Scene::from_file(const std::string& path) {
  Scene s;
  s.file = path;
  s.table = parse_scene_file(path);
  s.spec = load_scene_table(s.table, s.file);
  return s;
}

Scene Scene::from_dict(const py::dict& d, const std::string& label) {
  Scene s;
  s.file = label;
  s.table = table_of(d, "");
  s.spec = load_scene_table(s.table, s.file);
  return s;
}

void Scene::set(const std::string& key, const py::handle& value) {
  toml::table changed = table;
  try {
    set_scene_value(changed, key, std::move(*to_toml(value, key)));
  } catch (const SceneError& e) {
    throw SceneError(file + ": " + key + ": " + e.what());
  }
  spec = load_scene_table(changed, file);  // refused like the file: nothing changes
  table = std::move(changed);
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", R"(A validated scene (docs/scene.md).

Scene(path) reads a scene file; Scene.from_dict(d) reads a dict of the same tables. Either is
validated whole, as `dem run` validates a file: SceneError names the field, value and reason.)")
      .def(py::init([](const py::object& path) { return Scene::from_file(path_of(path)); }), py::arg("path"))
      .def_static(
          "from_dict",
          [](const py::dict& d, const py::object& base_dir) {
            const std::string dir = base_dir.is_none() ? "" : path_of(base_dir) + "/";
            return Scene::from_dict(d, dir + "<dict>");
          },
          py::arg("tables"), py::arg("base_dir") = py::none(),
          "A scene from a dict of tables ({'scene': {'name': ...}, 'integrator': {...}, ...}); relative file "
          "paths in it are read from base_dir (default: the current folder).")
      .def("set", &Scene::set, py::arg("key"), py::arg("value"),
           "Sets the value at a dotted key ('integrator.dt', 'walls.0.material'; a missing key is added and "
           "then validated like the file's keys); the whole scene is validated again and SceneError leaves it "
           "unchanged.")
      .def("to_dict", [](const Scene& s) { return to_python(s.table); }, "The scene's tables as a dict (a copy).")
      .def("resolved",
           [](const Scene& s) { return py::module_::import("json").attr("loads")(resolved_scene_json(s.spec).dump()); },
           "Every value resolved, with defaults and units, as `dem resolve` writes it.")
      .def_property_readonly("file", [](const Scene& s) { return s.file; })
      .def_property_readonly("name", [](const Scene& s) { return s.spec.name; })
      .def_property_readonly("dt", [](const Scene& s) { return s.spec.dt; })
      .def_property_readonly("n_discs", [](const Scene& s) { return s.spec.discs.size(); })
      .def("__repr__", [](const Scene& s) {
        return "<dem.Scene " + s.spec.name + " (" + s.file + "), " + std::to_string(s.spec.discs.size()) + " discs>";
      });
}

}  // namespace dem::python
