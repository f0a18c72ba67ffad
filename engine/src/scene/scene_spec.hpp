// A scene as the engine runs it (docs/scene.md): every value resolved and validated, with its
// unit and default. Read by scene.hpp's load_scene; the shear tables (shear_scene.hpp) add theirs.
#pragma once

#include <string>
#include <vector>

#include "physics/clusters.hpp"
#include "physics/disc_order.hpp"
#include "physics/geometry.hpp"
#include "physics/model.hpp"
#include "scene/scene_error.hpp"
#include "scene/shear_spec.hpp"
#include "scene/units.hpp"

namespace dem {

// Limits checked before anything is allocated (docs/scene.md, "Limits"): a scene past them is
// refused with a message, never allowed to exhaust memory or time.
constexpr long kMaxDiscs = 50'000'000;        // discs in a fill
constexpr double kBytesPerDisc = 1024;        // memory estimate per disc (world, lists, outputs)
constexpr long kMaxThreads = 256;             // integrator.threads, --threads
constexpr long kMaxMaterials = 1000;          // [materials] (pair tables are n^2)
constexpr double kMaxCoordinate = 1e15;       // |coordinates|, radii, silo sizes (squares stay finite)
constexpr double kMaxSteps = 1e12;            // end.time / dt and discharge.time / dt
constexpr long kMaxProfileBins = 100'000;     // wall length / output.profile_bin, per wall
constexpr long kMaxSnapshots = 10'000;        // discharge.snapshots
constexpr double kMaxSceneBytes = 1 << 30;    // scene file size

struct DiscInit {
  double x, y, r;
  int material;
  double vx = 0, vy = 0, omega = 0;  // [cm/s], [1/s]: fill.velocities reads them from the file
};

// Section 5(2): opening the slit from the rested fill, the outlet below it, and what is recorded.
struct DischargeSpec {
  bool enabled = false;
  double time = 1.0;            // [s] simulated after opening
  std::string gate = "gate";    // wall removed at opening
  double outlet_depth = 4.0;    // [cm] discs this far below the floor leave the computation
  double jam_time = 0.3;        // [s] no removal for this long while discs remain: a jam
  bool remove_keystone = false; // note 4: remove the arch's crown disc and go on (else stop)
  double series_interval = 0.005;  // [s] wall-force sampling
  double peak_window = 0.05;       // [s] moving-average window of the windowed peak ratio
  std::vector<double> snapshots = {0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0};  // [s] after opening
  double surface_column = 4.0;     // [cm] width of the surface columns at the walls and centre
};

// output.vtu: ASCII or binary VTU files (auto: binary above kVtuBinaryAbove discs), or none (the
// CSV files alone, for runs whose files are read by programs: no VTU, no PVD index).
enum class VtuChoice { automatic, ascii, binary, none };
constexpr std::size_t kVtuBinaryAbove = 10'000;

struct SceneSpec {
  std::string file, name, description;
  Units units = Units::cgs;        // [physics] units: the defaults with a unit and the words printed
  std::vector<std::string> sets;   // the --set assignments read into it (ensemble identities)
  double gx = 0, gy = -980.0;      // [physics] gravity [cm/s^2] (default_gravity_y of the units)
  Scheme scheme = Scheme::paper_eq19;
  double dt = 0;                   // [s]
  bool force_dt = false;
  int threads = 1;                 // [integrator] threads of the force and integration loops
  bool thread_choice = true;       // [integrator] thread_choice = "auto": a run steps with the faster of threads and 1 (run/thread_choice.hpp)
  DiscOrder disc_order = DiscOrder::automatic;  // [integrator] re-sort the discs into cell order (disc_order.hpp)
  ContactOptions contact;
  std::vector<std::string> material_names;
  std::vector<double> density;     // [g/cm^3]; 0 for obstacle-only materials
  std::vector<PairProps> props;    // n x n
  std::vector<char> props_set;
  Geometry geometry;
  bool has_silo = false;
  double silo_width = 0, silo_height = 0, slit_width = 0;
  bool slit_open = false;
  std::vector<DiscInit> discs;
  std::string fill_summary;
  double max_initial_overlap = 0;  // [fill] accepted initial overlap, fraction of the smaller radius
  double skin = 0, cell = 0;       // [neighbor]
  double end_time = 0;             // [end]
  bool stop_at_rest = true;
  double rest_factor = 1e-4;
  double max_overlap_fraction = 0.5;
  double max_energy_gain = 0.05;   // end.max_energy_gain: energy created beyond this x scale stops the run
  std::string start_from;          // [start] from: a saved state (skips the fill)
  DischargeSpec discharge;         // [discharge]
  ShearBoxSpec shear_box;          // [shear_box], [shear] (paper 2)
  ClusterSpec clusters;            // [clusters] (paper 2)
  long max_discs = kMaxDiscs;      // SceneOverrides::max_discs or kMaxDiscs
  double profile_bin = 0;          // [output]
  double checkpoint_every = 0;     // [s] simulated; 0: no checkpoints (--checkpoint-every overrides)
  bool progress = true;
  bool rotation_angle = false;     // [output] integrate and write each disc's rotation angle phi
  double thermo_interval = 0.01;   // [s] simulated time between rows of thermo.csv
  double snapshot_interval = 0;    // [s] simulated time between the run's periodic snapshots; 0: none
  double progress_interval = 2;    // [s] wall time between progress lines
  VtuChoice vtu = VtuChoice::automatic;

  // Whether the run writes VTU files and their PVD indexes (output.vtu != "none").
  bool vtu_files() const { return vtu != VtuChoice::none; }
  // Whether the VTU files of a world of n discs are binary (output.vtu).
  bool vtu_binary(std::size_t n) const {
    return vtu == VtuChoice::binary || (vtu == VtuChoice::automatic && n > kVtuBinaryAbove);
  }
};

// What the command line changes in a scene (0 / empty: nothing).
struct SceneOverrides {
  double dt = 0;              // 0: none
  std::string scheme;         // "": none
  double end_time = 0;        // 0: none
  bool force_dt = false;
  int threads = 0;            // 0: none
  std::string from;           // "": none; a state file to start from
  long max_discs = 0;         // 0: kMaxDiscs; lower for fuzzing (engine/fuzz)
  std::vector<std::string> sets;  // "KEY=VALUE" (--set), applied to the table before it is read
  bool no_vtu = false;        // --no-vtu: output.vtu = "none" (no part of an ensemble's identity)
};

}  // namespace dem
