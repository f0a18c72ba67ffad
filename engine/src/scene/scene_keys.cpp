#include "scene/scene_keys.hpp"

#include <algorithm>
#include <cstdint>
#include <map>

#include "scene/scene_error.hpp"

namespace dem {

namespace {

using Keys = std::vector<std::string>;

// Table patterns: "walls[]" is every entry of [[walls]], "materials.*" every material.
const std::map<std::string, Keys>& schema() {
  static const std::map<std::string, Keys> s = {
      {"", {"scene", "physics", "integrator", "contact", "materials", "pairs", "silo", "walls", "points", "fill",
            "end", "neighbor", "start", "discharge", "output", "shear_box", "shear", "clusters"}},
      {"scene", {"name", "description"}},
      {"physics", {"units", "gravity"}},
      {"integrator", {"scheme", "dt", "force_dt", "threads", "disc_order", "thread_choice"}},
      {"contact", {"normal_spring", "no_tension", "friction_cap", "lever_arm"}},
      {"materials.*", {"density"}},
      {"pairs[]", {"materials", "kn", "kn_rho_g", "ks", "ks_rho_g", "eta_n", "eta_n_rho_g", "eta_s", "eta_s_rho_g", "mu"}},
      {"silo", {"width", "height", "slit_width", "slit", "wall_material", "point_material"}},
      {"walls[]", {"name", "from", "to", "material", "group", "velocity", "move_from", "move_until"}},
      {"points[]", {"name", "at", "material", "group"}},
      {"fill", {"type", "material", "s", "radius", "gap", "rows", "count", "discs", "file", "velocities",
                "max_initial_overlap"}},
      {"end", {"time", "stop_at_rest", "rest_factor", "max_overlap", "max_energy_gain"}},
      {"neighbor", {"skin", "cell"}},
      {"start", {"from"}},
      {"discharge", {"time", "gate", "outlet_depth", "jam_time", "on_jam", "series_interval", "peak_window",
                     "surface_column", "snapshots"}},
      {"output", {"profile_bin", "progress", "rotation_angle", "checkpoint_every", "thermo_interval",
                  "snapshot_interval", "progress_interval", "vtu"}},
      {"shear_box", {"width", "height", "wall_length", "wall_material", "plate_material", "plate_volume",
                     "plate_density", "plate_gap", "plate_overhang", "plate_horizontal"}},
      {"shear", {"rate", "max_strain", "sample_strain", "snapshots"}},
      {"clusters", {"bonds", "touch_tolerance", "members"}},
  };
  return s;
}

// "walls[2]" -> "walls[]", "materials.sand" -> "materials.*".
std::string pattern_of(const std::string& path) {
  if (path.rfind("materials.", 0) == 0) return "materials.*";
  const std::size_t open = path.find('[');
  return open == std::string::npos ? path : path.substr(0, open) + "[]";
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string field(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

// An unknown key of a table: where it is and its line (keys --set added have none: last).
struct Unknown {
  std::string path, key;
  std::uint32_t line = UINT32_MAX;
};

// The table's unknown keys appended to `out`.
void check_table(const toml::table& t, const std::string& path, std::vector<Unknown>& out) {
  const Keys* known = scene_keys(path);
  if (!known) return;
  for (const auto& [k, v] : t)
    if (std::find(known->begin(), known->end(), k.str()) == known->end())
      out.push_back({path, std::string(k.str()), v.source().begin.line ? v.source().begin.line : UINT32_MAX});
}

}  // namespace

const std::vector<std::string>* scene_keys(const std::string& path) {
  const auto it = schema().find(pattern_of(path));
  return it == schema().end() ? nullptr : &it->second;
}

std::string closest_key(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_d = 0;
  for (const std::string& k : known) {
    const std::size_t d = edit_distance(key, k);
    if (best.empty() || d < best_d) {
      best = k;
      best_d = d;
    }
  }
  // Close enough to be meant: a typo or two, fewer in a short key ("dtt" -> "dt", not "x" -> "s").
  const std::size_t shorter = std::min(key.size(), best.size());
  return !best.empty() && best_d <= std::max<std::size_t>(1, std::min<std::size_t>(3, shorter / 3)) && best_d < shorter
             ? best
             : "";
}

std::string unknown_key_reason(const std::string& path, const std::string& key) {
  const Keys* known = scene_keys(path);
  if (!known) return "unknown key";
  const std::string near = closest_key(key, *known);
  if (!near.empty()) return "unknown key; did you mean `" + near + "`?";
  std::string list;
  for (const std::string& k : *known) list += (list.empty() ? "" : ", ") + k;
  return "unknown key (" + std::string(path.empty() ? "the tables are " : "known: ") + list + ")";
}

void check_scene_keys(const toml::table& root, const std::string& file) {
  std::vector<Unknown> unknown;
  check_table(root, "", unknown);
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    if (const toml::table* t = v.as_table()) {
      check_table(*t, key, unknown);
      if (key == "materials")
        for (const auto& [name, m] : *t)
          if (const toml::table* mt = m.as_table()) check_table(*mt, "materials." + std::string(name.str()), unknown);
    } else if (const toml::array* a = v.as_array()) {
      for (std::size_t i = 0; i < a->size(); ++i)
        if (const toml::table* e = a->get(i)->as_table()) check_table(*e, key + "[" + std::to_string(i) + "]", unknown);
    }
  }
  if (unknown.empty()) return;
  // The first in the file.
  const Unknown& u = *std::min_element(unknown.begin(), unknown.end(),
                                       [](const Unknown& a, const Unknown& b) { return a.line < b.line; });
  std::string msg = file + ": " + field(u.path, u.key) + ": " + unknown_key_reason(u.path, u.key);
  if (u.line != UINT32_MAX) msg += " (line " + std::to_string(u.line) + ")";
  throw SceneError(msg);
}

}  // namespace dem
