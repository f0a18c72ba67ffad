// The engine's Python module `dem._engine` (pybind11), whose names the package `dem` exports
// (dem/__init__.py): scenes (scene_object.cpp) and simulations (simulation.cpp) over the engine's
// own reader, world and run harness (docs/python.md).
#include <pybind11/pybind11.h>

#include "scene/scene.hpp"
#include "scene_object.hpp"

namespace dem::python {
void bind_simulation(pybind11::module_& m);
}

PYBIND11_MODULE(_engine, m) {
  m.doc() = "2D discrete-element engine of Kiyama & Fujimura (1983): scenes, runs and their arrays (docs/python.md)";
  m.attr("__version__") = DEM_VERSION;
  m.attr("build") = DEM_BUILD_ID;
  // A scene that cannot run: the message names the file (or <dict>), the field, value and reason.
  pybind11::register_exception<dem::SceneError>(m, "SceneError", PyExc_ValueError);
  dem::python::bind_scene(m);
  dem::python::bind_simulation(m);
  m.def(
      "load",
      [](const pybind11::object& source) {
        if (pybind11::isinstance<pybind11::dict>(source))
          return dem::python::Scene::from_dict(source.cast<pybind11::dict>(), "<dict>");
        return dem::python::Scene::from_file(pybind11::str(pybind11::module_::import("os").attr("fspath")(source)));
      },
      pybind11::arg("source"), "A scene from a file path or a dict of tables (Scene(path), Scene.from_dict(d)).");
}
