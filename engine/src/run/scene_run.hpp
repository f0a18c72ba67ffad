// The run of a scene: its phases in order (the fill, unless it starts from a state file; the
// discharge; the shear) through one runner (runner.hpp), with checkpoints, resume and the
// summary the outputs need. `dem run` and `dem ensemble` both run scenes through it.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/outputs.hpp"
#include "io/run_log.hpp"
#include "run/checkpoint.hpp"
#include "run/discharge.hpp"
#include "run/fill_phase.hpp"
#include "run/runner.hpp"
#include "run/shear_phase.hpp"

namespace dem {

struct SceneSpec;
class World;

class SceneRun {
 public:
  // out_dir holds the phases' files, the last good state and the positions at opening.
  SceneRun(const SceneSpec& spec, World& w, const std::string& out_dir);

  // Checkpoints every `every_steps` steps (0: none) and on a stop request, into `path`.
  void set_checkpoints(long every_steps, const std::string& path, const CheckpointKey& key);
  // Continues from a checkpoint (replaces the world's state). Throws std::runtime_error with the
  // reason (another engine, scene or option set, a damaged file, a wall series cut short).
  void resume(const std::string& path, const CheckpointKey& key);
  // The phase a resumed run goes on in ("fill", "discharge", "shear").
  const char* phase_name() const;

  // Runs the phases from where the run stands to the end, a stop request or instability.
  // `print`: the lines between phases (opening the slit, shearing) on stdout.
  Status run(bool progress, bool print);

  // For summary.json: the status, rest, wall time, and the last good discs of an unstable run;
  // `extra` gets the phases' entries ("status", "reason", "discharge", "shear").
  RunSummary summary(nlohmann::ordered_json& extra);
  // The last good state's file is removed (the outputs hold it when it was needed).
  void discard_kept();

  Status status = Status::running;
  RunLog* log = nullptr;  // where the lines between phases go (printed or not as the log echoes)
  Runner runner;
  FillPhase fill;
  std::unique_ptr<DischargePhase> discharge;  // null for scenes without [discharge]
  std::unique_ptr<ShearPhase> shear;          // null for scenes without [shear]

 private:
  void checkpoint(const Phase& current);
  const SceneSpec& spec_;
  World& w_;
  std::vector<Phase*> phases_;
  std::size_t current_ = 0;   // index in phases_ of the phase running (or to run)
  bool fresh_ = true;         // the current phase starts at its begin
  bool from_state_ = false;   // no fill: the run starts from a state file
  std::string ckpt_path_;
  CheckpointKey key_;
  Discs good_;                // the last good discs, loaded for an unstable run's outputs
};

// The fill alone (the scene's other phases not run), its last good state in memory: for tests
// and studies that open or shear the world themselves.
Status run_fill(const SceneSpec& spec, World& w, Rest* rest = nullptr);

}  // namespace dem
