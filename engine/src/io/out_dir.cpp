#include "io/out_dir.hpp"

#include <filesystem>
#include <system_error>
#include <vector>

namespace dem {

namespace {

// Every file a run writes into its folder (docs/outputs.md), and the pictures drawn from them.
const char* const kRunFiles[] = {
    "summary.json", "run.log", "thermo.csv", "snapshots.pvd", "discs.csv", "discs.vtu", "contacts.csv",
    "contacts.vtu", "walls.vtu", "wall_profiles.csv", "removals.csv", "flow_series.csv", "wall_series.csv",
    "wall_totals_series.csv", "discharge_discs.pvd", "discharge_contacts.pvd", "discharge_snapshots.csv",
    "shear_series.csv", "shear_planes.csv", "checkpoint.dem", "last_good.bin", "opening_positions.bin", "member.json",
    "network.png", "side_walls.png", "frames.png", "wall_ratios.png", "flow.png"};

// The snapshots' names: discs_*, contacts_*, walls_*, step_* and index.json.
bool snapshot_file(const std::string& name) {
  for (const char* prefix : {"discs_", "contacts_", "walls_", "step_"})
    if (name.rfind(prefix, 0) == 0) return true;
  return name == "index.json" || name == "index.json.tmp";
}

}  // namespace

int clear_run_outputs(const std::string& dir) {
  namespace fs = std::filesystem;
  int removed = 0;
  std::error_code ec;
  for (const char* name : kRunFiles)
    for (const std::string& f : {std::string(name), std::string(name) + ".tmp"})
      if (fs::is_regular_file(dir + "/" + f, ec)) removed += fs::remove(dir + "/" + f, ec);
  const fs::path snaps = fs::path(dir) / "snapshots";
  if (fs::is_directory(snaps, ec)) {
    std::vector<fs::path> old;  // listed first, removed after: no removal while the folder is read
    for (const auto& e : fs::directory_iterator(snaps, ec))
      if (e.is_regular_file(ec) && snapshot_file(e.path().filename().string())) old.push_back(e.path());
    for (const fs::path& f : old) removed += fs::remove(f, ec);
    if (fs::is_empty(snaps, ec)) fs::remove(snaps, ec);
  }
  return removed;
}

}  // namespace dem
