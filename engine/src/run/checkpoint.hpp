// Checkpoints of `dem run` (docs/outputs.md): the world's state with its contact history and
// the neighbour lists exactly as they were, the fill's progress, and in a discharge everything
// it carries (DischargeState), with the engine version and the scene's hash. A run resumed from
// one ends bit-identical to the run never stopped.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "run/discharge.hpp"
#include "run/run.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace dem {

// What a checkpoint must match to be resumed.
struct CheckpointKey {
  std::string engine;         // "dem 0.1.0 (GNU 12.2.0 Release)": version and build
  std::uint64_t scene_hash;   // FNV-1a 64 of the scene file's bytes
  std::string overrides;      // the command-line options that change the run (--dt, ...)
};

CheckpointKey checkpoint_key(const std::string& scene_file, const SceneOverrides& ov);

// FNV-1a 64 of a file's bytes (throws std::runtime_error when it cannot be read).
std::uint64_t file_hash(const std::string& path);

// The checkpoint file of an output directory.
std::string checkpoint_path(const std::string& out_dir);

// Writes atomically (NAME.tmp, then renamed). `discharge` is null during the fill.
void write_checkpoint(const std::string& path, const CheckpointKey& key, const World& w, const RunResult& fill,
                      const DischargeState* discharge);

// Reads a checkpoint into a world built from the scene (build_world): the world, the fill's
// RunResult, and the discharge state when it was written during a discharge (in_discharge).
// Throws std::runtime_error with the reason (another engine version, another scene, other
// options, a damaged file).
void read_checkpoint(const std::string& path, const CheckpointKey& key, World& w, RunResult& fill,
                     DischargeState& discharge, bool& in_discharge);

}  // namespace dem
