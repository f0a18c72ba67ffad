// Checkpoints of `dem run` (docs/outputs.md): the world's state with its contact history and
// the neighbour lists exactly as they were, the runner's state (guard, last good state, clock),
// the fill's rest measure and the state of the phase running (phase.hpp), with the engine
// version and the scene's hash. A run resumed from
// one ends bit-identical to the run never stopped.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

#include "run/fill_phase.hpp"
#include "run/runner.hpp"
#include "scene/scene.hpp"

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

struct BinaryIn;

// Writes atomically (NAME.tmp, then renamed) in `phase` (its name); `state`: the phase whose
// own state goes with it (null for the fill, whose rest measure is always written).
void write_checkpoint(const std::string& path, const CheckpointKey& key, const World& w, const Runner& runner,
                      const Rest& rest, const std::string& phase, const Phase* state);

// Reads a checkpoint into a world built from the scene (build_world), the runner and the rest
// measure; load_phase(name, in) reads the phase's own state (for a phase other than the fill).
// Throws std::runtime_error with the reason (another engine version, another scene, other
// options, a damaged file).
void read_checkpoint(const std::string& path, const CheckpointKey& key, World& w, Runner& runner, Rest& rest,
                     std::string& phase, const std::function<void(const std::string&, BinaryIn&)>& load_phase);

}  // namespace dem
