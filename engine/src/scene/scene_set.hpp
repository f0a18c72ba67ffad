// Changing a scene's value by key before it is validated (`dem run --set KEY=VALUE`, the Python
// module's Scene.set): the parsed table is edited and then read like a file, so a wrong key or
// value is refused with the same message as in the file.
#pragma once

#include <toml++/toml.h>

#include <string>

namespace dem {

// Sets the value at a dotted key: "integrator.dt", "walls.0.material" or "walls[0].material"
// (an index picks an entry of an array). Tables missing on the way are made, and a key the
// scene does not have is added: the reader then refuses an unknown one as in a file. Throws
// SceneError naming the key when the path cannot be followed (an index out of range, a value
// where a table is needed).
void set_scene_value(toml::table& root, const std::string& key, toml::node&& value);

// "KEY=VALUE": VALUE is read as a TOML value (5e-5, 2, true, [1, 2], "text"), or else taken as
// a string (velocity_verlet). Throws SceneError starting "--set KEY=VALUE: ".
void apply_assignment(toml::table& root, const std::string& assignment);

}  // namespace dem
