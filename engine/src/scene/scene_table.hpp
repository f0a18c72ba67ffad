// A scene as its parsed TOML table: read from a file, changed by key (scene_set.hpp), then
// validated into a SceneSpec by the same reader whichever way the table was made (a file,
// `--set`, a Python dict), so every error names the field the same way.
#pragma once

#include <toml++/toml.h>

#include <string>

#include "scene/scene_spec.hpp"

namespace dem {

// The file itself: a regular file within the size limit, valid TOML (SceneError otherwise).
toml::table parse_scene_file(const std::string& path);

// Validates a parsed scene; `file` names it in errors, and relative paths in it (fill.file,
// start.from) are read from the folder of `file`. ov.sets are not applied here (load_scene
// applies them to the table first).
SceneSpec load_scene_table(const toml::table& root, const std::string& file, const SceneOverrides& ov = {});

}  // namespace dem
