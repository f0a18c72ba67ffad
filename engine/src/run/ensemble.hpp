// Ensembles: discharge is chaotic, so a result is a mean over members whose initial positions
// differ by a tiny seeded amount. Members run in parallel threads (each a separate World).
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace dem {

struct EnsembleOptions {
  int members = 8;
  unsigned long seed = 1;
  double perturb = 1e-4;  // [cm] each disc centre moves by a uniform amount in [-perturb, perturb]
  int jobs = 0;           // 0: all cores
  std::vector<std::string> command;  // the command line, for each member's summary.json
};

// Runs the members into out_dir/member_KK and writes out_dir/ensemble.json; returns the
// process exit code: 0, or, when every member failed, 3 (all unstable) or 4 (some could not
// run). Throws SceneError for bad input.
int run_ensemble(const SceneSpec& spec, const EnsembleOptions& opt, const std::string& out_dir, bool quiet);

// Member k alone into out_dir/member_KK: the same member, bit for bit, as in run_ensemble with
// the same seed and perturbation (for job arrays across machines). Exit code 0, 3 unstable, 4 failed.
int run_member_alone(const SceneSpec& spec, const EnsembleOptions& opt, int k, const std::string& out_dir, bool quiet);

// Member k run in a reference code (dem ensemble --member K --engine CODE): clears
// out_dir/member_KK, writes there member_start.csv (x,y of member k's start, the scene's discs in
// their order, perturbed exactly as run_member_alone perturbs them) and member.json (the
// identity, with the code and the settling time: members of another code are another ensemble),
// and returns the folder, for `dem.compare.engine_run --member-start` to run and fill in.
std::string prepare_engine_member(const SceneSpec& spec, const EnsembleOptions& opt, int k, const std::string& out_dir,
                                  const std::string& code, double settle);

// Gathers finished members (out_dir/member_KK with summary.json and member.json) into
// out_dir/ensemble.json, the same as run_ensemble writes. Refuses members of another ensemble
// (scene, seed, perturbation, scheme, dt) and missing ones (members_wanted: 0 = those found,
// which must be 0..n-1). Throws std::runtime_error naming the folder; returns the exit code.
int merge_ensemble(const std::string& out_dir, int members_wanted, bool quiet);

}  // namespace dem
