#include "run/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "io/binary.hpp"
#include "io/files.hpp"
#include "io/outputs.hpp"
#include "io/vtu.hpp"
#include "measures/group_loads.hpp"
#include "physics/world.hpp"
#include "scene/scene.hpp"

namespace dem {

namespace {
long every(double interval, double dt) {
  return interval > 0 ? std::max(1L, static_cast<long>(std::llround(interval / dt))) : 0;
}
}  // namespace

void Recorder::configure(const SceneSpec& spec, const std::string& out_dir, double dt) {
  spec_ = &spec;
  out_ = out_dir;
  thermo_every_ = every(spec.thermo_interval, dt);
  snapshot_every_ = every(spec.snapshot_interval, dt);
}

void Recorder::thermo_row(const World& w, const char* phase) {
  thermo.sample(w, phase, measure_group_loads(w, thermo.groups(w)));
}

void Recorder::phase_start(const World& w, const char* phase) {
  if (!active()) return;
  thermo_row(w, phase);
  if (snapshot_every_ > 0 && w.steps % snapshot_every_ == 0 && snapshots.last_step() != w.steps) snapshot(w);
}

void Recorder::after_step(const World& w, const char* phase) {
  if (!active()) return;
  if (thermo_every_ > 0 && w.steps % thermo_every_ == 0) thermo_row(w, phase);
  if (snapshot_every_ > 0 && w.steps % snapshot_every_ == 0 && snapshots.last_step() != w.steps) snapshot(w);
}

void Recorder::phase_end(const World& w, const char* phase, Status status) {
  // An interrupted phase goes on after a resume: its end row would not be in the run never stopped.
  if (!active() || status == Status::interrupted) return;
  thermo_row(w, phase);
}

std::string Recorder::write_walls(const World& w, const std::string& stem) const {
  const std::string rel = "snapshots/walls_" + stem + ".vtu";
  if (spec_->vtu_files()) write_walls_vtu(out_ + "/" + rel, w.geometry, spec_->vtu_binary(w.discs.size()));
  return rel;
}

void Recorder::phase_snapshot(const World& w, const std::string& stem, const OpeningPositions* at_open,
                              const char* collection, double t) {
  const std::string dir = out_ + "/snapshots";
  write_disc_files(dir, "discs_" + stem, *spec_, w.discs, at_open, &w);
  write_contact_files(dir, "contacts_" + stem, w, spec_->vtu_binary(w.discs.size()), spec_->vtu_files());
  if (active())
    snapshots.add(on_step_grid(w.time, w.dt), w.steps, "snapshots/discs_" + stem + ".vtu", write_walls(w, stem),
                  "snapshots/contacts_" + stem + ".vtu");
  if (!collection) return;
  Collection& c = collections_[collection];
  const std::string when = time_text(on_step_grid(t, w.dt));
  if (spec_->vtu_files()) {
    c.discs += "    <DataSet timestep=\"" + when + "\" file=\"snapshots/discs_" + stem + ".vtu\"/>\n";
    c.contacts += "    <DataSet timestep=\"" + when + "\" file=\"snapshots/contacts_" + stem + ".vtu\"/>\n";
  } else {
    c.discs += when + ",snapshots/discs_" + stem + ".csv,snapshots/contacts_" + stem + ".csv\n";
  }
}

void Recorder::write_collection(const std::string& name, const std::string& dir) const {
  const auto it = collections_.find(name);
  const Collection empty;
  const Collection& c = it == collections_.end() ? empty : it->second;
  if (!spec_->vtu_files()) {
    write_file_atomic(dir + "/" + name + "_snapshots.csv", "t,discs,contacts\n" + c.discs);
    return;
  }
  for (auto [part, body] : {std::pair{"_discs.pvd", &c.discs}, std::pair{"_contacts.pvd", &c.contacts}})
    write_file_atomic(dir + "/" + name + part, "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                                                 "  <Collection>\n" + *body + "  </Collection>\n</VTKFile>\n");
}

void Recorder::snapshot(const World& w) {
  std::filesystem::create_directories(out_ + "/snapshots");
  char stem[40];
  std::snprintf(stem, sizeof stem, "step_%09ld", w.steps);
  const std::string dir = out_ + "/snapshots", s = stem;
  const bool binary = spec_->vtu_binary(w.discs.size());
  write_disc_files(dir, s + "_discs", *spec_, w.discs, nullptr, &w);
  write_contact_files(dir, s + "_contacts", w, binary, spec_->vtu_files());
  if (spec_->vtu_files()) write_walls_vtu(dir + "/" + s + "_walls.vtu", w.geometry, binary);
  snapshots.add(on_step_grid(w.time, w.dt), w.steps, "snapshots/" + s + "_discs.vtu", "snapshots/" + s + "_walls.vtu",
                "snapshots/" + s + "_contacts.vtu");
}

void Recorder::write() const {
  if (!active()) return;
  if (!thermo.text().empty()) write_file_atomic(out_ + "/thermo.csv", thermo.text());
  if (!snapshots.empty() && spec_->vtu_files()) snapshots.write(out_ + "/snapshots.pvd");  // it indexes VTU files
}

void Recorder::save(BinaryOut& o) const {
  o.str(thermo.text());
  o.put(thermo.last_step());
  o.str(snapshots.entries());
  o.put(snapshots.last_step());
  o.put<std::uint64_t>(collections_.size());
  for (const auto& [name, c] : collections_) {
    o.str(name); o.str(c.discs); o.str(c.contacts);
  }
}

void Recorder::load(BinaryIn& r) {
  std::string text = r.str();
  const long last = r.get<long>();
  std::string entries = r.str();
  const long snap_last = r.get<long>();
  thermo.restore(std::move(text), last);
  snapshots.restore(std::move(entries), snap_last);
  collections_.clear();
  for (std::uint64_t n = r.count(64); n > 0; --n) {
    std::string name = r.str(1 << 10);
    Collection& c = collections_[name];
    c.discs = r.str();
    c.contacts = r.str();
  }
}

}  // namespace dem
