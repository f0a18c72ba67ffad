// dem.Scene: a scene as its parsed TOML table and the SceneSpec validated from it. Every change
// (Scene.set) edits a copy of the table and validates it whole, so a scene object is always valid.
#pragma once

#include <pybind11/pybind11.h>
#include <toml++/toml.h>

#include <string>

#include "scene/scene_spec.hpp"

namespace dem::python {

struct Scene {
  toml::table table;
  std::string file;  // names the scene in errors; relative paths are read from its folder
  SceneSpec spec;

  static Scene from_file(const std::string& path);
  // `label`: the name errors give the dict; its folder is where relative paths are read from.
  static Scene from_dict(const pybind11::dict& d, const std::string& label);
  void set(const std::string& key, const pybind11::handle& value);
};

void bind_scene(pybind11::module_& m);

}  // namespace dem::python
