// Scene files (TOML, docs/scene.md): reading, validation (scene_spec.hpp holds the result), and
// building a World from a scene.
// Everything is checked before any step; errors name the file, the field, the value, the reason.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "physics/stability.hpp"
#include "scene/scene_spec.hpp"

namespace dem {

class World;

// Reads and validates; throws SceneError. Overrides (SceneOverrides, scene_spec.hpp) come from the CLI.
SceneSpec load_scene(const std::string& path, const SceneOverrides& ov = {});

// Refuses a disc whose radius, place, mass or start motion is not finite or beyond the limits.
void check_disc_values(const SceneSpec& s);
// Refuses overlapping discs and discs outside the walls (throws SceneError).
void check_initial_discs(const SceneSpec& s);

// Builds the world; throws SceneError for a dt above the scheme's bound (unless forced). Returns
// the bounds it checked, for the run's header (computed once: the cluster bound takes a while).
StabilityReport build_world(const SceneSpec& s, World& w);
// The same, freeing the scene's disc list (s.discs) once the world holds the discs and before it
// builds its contact lists: at a million discs the list (56 bytes a disc) would otherwise add
// to the peak memory of the run. For callers that no longer need s.discs.
StabilityReport build_world_releasing_discs(SceneSpec& s, World& w);

Scheme parse_scheme(const std::string& s, bool& ok);

}  // namespace dem
