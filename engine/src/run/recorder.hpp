// What the run records in every phase besides the phases' own files: thermo.csv (io/thermo.hpp)
// every output.thermo_interval, periodic snapshots every output.snapshot_interval, and the run's
// one ParaView collection snapshots.pvd of every snapshot (periodic, the discharge's and the
// shear's), and a phase's own collection of its snapshots (the discharge's). Steps are counted on the world's step count, so a resumed run records the same steps.
#pragma once

#include <map>
#include <string>

#include "io/pvd.hpp"
#include "io/thermo.hpp"
#include "run/status.hpp"

namespace dem {

class OpeningPositions;
class World;
struct SceneSpec;
struct BinaryOut;
struct BinaryIn;

class Recorder {
 public:
  // out_dir empty: records nothing (a fill run by a test in memory).
  void configure(const SceneSpec& spec, const std::string& out_dir, double dt);
  bool active() const { return !out_.empty(); }
  // Whether step `step` is a periodic snapshot's: its contacts need the step's pair totals.
  bool snapshot_due(long step) const { return active() && snapshot_every_ > 0 && step % snapshot_every_ == 0; }

  // Whether after_step records at `step` (a thermo row or a periodic snapshot): it reads the velocities.
  bool due(long step) const {
    return active() && ((thermo_every_ > 0 && step % thermo_every_ == 0) || snapshot_due(step));
  }
  // A phase's fresh start, each step the guard passed that leaves it running, and its end.
  void phase_start(const World& w, const char* phase);
  void after_step(const World& w, const char* phase);
  void phase_end(const World& w, const char* phase, Status status);

  // A phase's snapshot (the discharge's, the shear's): snapshots/discs_STEM and contacts_STEM
  // (.csv, and .vtu unless output.vtu = "none"; the discs with their displacements from `at_open`
  // when given) and, recording, walls_STEM.vtu with the snapshot's entry in snapshots.pvd, so
  // that the periodic snapshot of the same step is not written.
  // With `collection` (the discharge's "discharge"), the snapshot is also an entry at time t in
  // that phase's own collection, which write_collection writes.
  void phase_snapshot(const World& w, const std::string& stem, const OpeningPositions* at_open = nullptr,
                      const char* collection = nullptr, double t = 0);
  // A phase's own collection of its snapshots into dir: NAME_discs.pvd and NAME_contacts.pvd, or
  // (no VTU files to index) the rows of NAME_snapshots.csv.
  void write_collection(const std::string& name, const std::string& dir) const;

  // thermo.csv and snapshots.pvd as they stand.
  void write() const;

  void save(BinaryOut& o) const;
  void load(BinaryIn& r);

  Thermo thermo;
  PvdIndex snapshots;

 private:
  void snapshot(const World& w);
  void thermo_row(const World& w, const char* phase);
  std::string write_walls(const World& w, const std::string& stem) const;  // snapshots/walls_STEM.vtu
  struct Collection {
    std::string discs, contacts;  // the .pvd entries, or the .csv rows (discs)
  };
  std::map<std::string, Collection> collections_;
  const SceneSpec* spec_ = nullptr;
  std::string out_;
  long thermo_every_ = 0, snapshot_every_ = 0;  // [steps] 0: none
};

}  // namespace dem
