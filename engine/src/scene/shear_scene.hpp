// Scene tables of paper 2 (docs/scene.md): [shear_box], [shear] and [clusters]. Validated as
// strictly as the rest of the scene: unknown keys, wrong types, values out of range, disc
// indices out of range or in two clusters are refused with the file, field, value and reason.
#pragma once

#include <toml++/toml.h>

#include "scene/scene_spec.hpp"

namespace dem {

// Before the walls are read: [shear_box] adds its floor and side walls to s.geometry; [shear]
// and [clusters] are read. Throws SceneError.
void read_shear_tables(SceneSpec& s, const toml::table& root);

// After the fill: the plate goes above the highest disc; the clusters' disc indices are checked.
void finish_shear_tables(SceneSpec& s);

class World;
// The box's walls, plate and bonds in a world built from the scene (called by build_world).
void build_shear_world(const SceneSpec& s, World& w);

}  // namespace dem
