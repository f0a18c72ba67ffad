#include "scene/resolve.hpp"

#include <algorithm>

#include "physics/world.hpp"

namespace dem {

nlohmann::json resolved_scene_json(const SceneSpec& s) {
  using nlohmann::json;
  json j;
  j["format"] = "dem-resolved-scene 1";
  j["engine"] = std::string("dem ") + DEM_VERSION;
  j["name"] = s.name;
  j["file"] = s.file;
  j["gravity"] = {s.gx, s.gy};
  // Every number below is in the scene's unit system (physics.units): its name and the unit of
  // each kind of quantity, as the run header prints them.
  const UnitNames u = unit_names(s.units);
  j["units"] = {{"system", to_string(s.units)}, {"length", u.length},       {"velocity", u.velocity},
                {"acceleration", u.acceleration}, {"density", u.density}, {"mass", u.mass},
                {"force", u.force},                {"energy", u.energy},   {"stiffness", u.stiffness},
                {"time", "s"}};
  j["integrator"] = {{"scheme", to_string(s.scheme)}, {"dt", s.dt}, {"force_dt", s.force_dt}};
  j["contact"] = {{"normal_spring", to_string(s.contact.normal_spring)},
                  {"no_tension", to_string(s.contact.no_tension)},
                  {"friction_cap", to_string(s.contact.friction_cap)},
                  {"lever_arm", to_string(s.contact.lever_arm)}};
  json mats = json::array();
  for (std::size_t m = 0; m < s.material_names.size(); ++m)
    mats.push_back({{"name", s.material_names[m]}, {"density", s.density[m]}});
  j["materials"] = mats;
  const std::size_t n = s.material_names.size();
  json pairs = json::array();
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a; b < n; ++b)
      if (s.props_set[a * n + b]) {
        const PairProps& p = s.props[a * n + b];
        pairs.push_back({{"materials", {s.material_names[a], s.material_names[b]}},
                         {"kn", p.kn}, {"ks", p.ks}, {"eta_n", p.eta_n}, {"eta_s", p.eta_s}, {"mu", p.mu}});
      }
  j["pairs"] = pairs;
  json walls = json::array();
  for (const Wall& w : s.geometry.walls) {
    walls.push_back({{"name", w.name}, {"group", w.group}, {"from", {w.ax, w.ay}}, {"to", {w.bx, w.by}},
                     {"material", s.material_names[w.material]}, {"active", w.active}});
    if (w.moves())  // a prescribed translation (walls[].velocity), only where there is one
      walls.back()["motion"] = {{"velocity", {w.move_vx, w.move_vy}}, {"from", w.move_from}, {"until", w.move_until}};
  }
  j["walls"] = walls;
  json points = json::array();
  for (const Point& p : s.geometry.points)
    points.push_back({{"name", p.name}, {"group", p.group}, {"at", {p.x, p.y}},
                      {"material", s.material_names[p.material]}});
  j["points"] = points;
  if (s.has_silo)
    j["silo"] = {{"width", s.silo_width}, {"height", s.silo_height}, {"slit_width", s.slit_width},
                 {"slit_open", s.slit_open}};
  json discs = json::array();
  for (const DiscInit& d : s.discs) discs.push_back({d.x, d.y, d.r, d.material});
  j["discs"] = discs;  // [x, y, r, material index]
  // Start velocities (fill.velocities): [vx, vy, omega] per disc, only when some disc moves.
  const bool moving = std::any_of(s.discs.begin(), s.discs.end(),
                                  [](const DiscInit& d) { return d.vx != 0 || d.vy != 0 || d.omega != 0; });
  if (moving) {
    json v = json::array();
    for (const DiscInit& d : s.discs) v.push_back({d.vx, d.vy, d.omega});
    j["velocities"] = v;
  }
  j["fill"] = {{"max_initial_overlap", s.max_initial_overlap}};
  j["end"] = {{"time", s.end_time}, {"stop_at_rest", s.stop_at_rest}, {"rest_factor", s.rest_factor},
              {"max_overlap", s.max_overlap_fraction}};
  j["neighbor"] = {{"skin", s.skin}, {"cell", s.cell}};
  j["profile_bin"] = s.profile_bin;
  if (s.discharge.enabled) {
    const DischargeSpec& d = s.discharge;
    j["discharge"] = {{"time", d.time}, {"gate", d.gate}, {"outlet_depth", d.outlet_depth},
                      {"jam_time", d.jam_time}, {"remove_keystone", d.remove_keystone},
                      {"series_interval", d.series_interval}, {"peak_window", d.peak_window},
                      {"snapshots", d.snapshots}, {"surface_column", d.surface_column}};
  }
  if (s.shear_box.enabled) {  // paper 2 (docs/scene.md): the box's walls and plate are in "walls"
    const ShearBoxSpec& b = s.shear_box;
    j["shear_box"] = {{"width", b.width}, {"height", b.height}, {"wall_length", b.wall_length},
                      {"plate_material", s.material_names[b.plate_material]}, {"plate_volume", b.plate_volume},
                      {"plate_density", b.plate_density}, {"plate_mass", b.plate_mass}, {"plate_y", b.plate_y},
                      {"plate_horizontal", b.plate_follows_walls ? "with_walls" : "free"}};
    if (b.shear)
      j["shear"] = {{"rate", b.rate}, {"max_strain", b.max_strain}, {"sample_strain", b.sample_strain},
                    {"snapshots", b.snapshots}};
  }
  if (s.clusters.enabled)
    j["clusters"] = {{"bonds", to_string(s.clusters.bonds)}, {"touch_tolerance", s.clusters.touch_tolerance},
                     {"members", s.clusters.members}};
  return j;
}

}  // namespace dem
