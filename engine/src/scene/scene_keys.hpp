// The keys each table of a scene may hold. Every table's keys are checked against them before
// any value is read, so that a misspelt key is reported as itself (with the closest known key),
// never as the required key it was meant to be.
#pragma once

#include <toml++/toml.h>

#include <string>
#include <vector>

namespace dem {

// The known keys of the table at `path` ("integrator", "walls[2]", "materials.sand"; "" is the
// root), or nullptr where its keys are names the scene chooses ([materials]).
const std::vector<std::string>* scene_keys(const std::string& path);

// The known key closest to `key` by edit distance, or "" when none is close enough to be meant.
std::string closest_key(const std::string& key, const std::vector<std::string>& known);

// Refuses the first key, in every table of the scene, that scene_keys does not know (SceneError:
// "FILE: integrator.schem: unknown key; did you mean `scheme`? (line 12)").
void check_scene_keys(const toml::table& root, const std::string& file);

// The reason given for an unknown key of the table at `path`.
std::string unknown_key_reason(const std::string& path, const std::string& key);

}  // namespace dem
