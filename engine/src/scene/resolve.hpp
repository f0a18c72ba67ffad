// The resolved scene as JSON: every number the engine will use (absolute pair constants, the
// silo's walls and points, every disc). The comparison layer translates this, not the TOML,
// so that LIGGGHTS and YADE get exactly the engine's values.
#pragma once

#include <nlohmann/json.hpp>

#include "scene/scene.hpp"

namespace dem {

nlohmann::json resolved_scene_json(const SceneSpec& s);

}  // namespace dem
