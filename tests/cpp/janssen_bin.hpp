// The Janssen bin of the bit-for-bit tests: 4500 discs of radii 0.4-0.6 cm in a 15 cm bin
// (reference_inputs/scenes/janssen_w15.toml), whose loose start packs into contact within a few
// hundred steps.
#pragma once

#include <string>

#include "scene/scene.hpp"

namespace dem::testing {

// At 2e-5 s, the step these tests' step counts were set for: 1.2x the bound the bin's 0.4 cm
// discs set (the scene itself runs at 1.6e-5 s). Forced: the tests compare the bits of two
// paths through the engine, which a small disc rattling at the bound does not change.
inline SceneSpec janssen_bin(int threads = 1) {
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/janssen_w15.toml");
  spec.threads = threads;
  spec.dt = 2e-5;
  spec.force_dt = true;
  return spec;
}

}  // namespace dem::testing
