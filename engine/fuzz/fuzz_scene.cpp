// libFuzzer target of the scene reader (scripts/fuzz.sh): reads the input as a scene file,
// validates it, builds the world and takes a few steps. The contract under test: any input
// gives either a world that steps or a SceneError (a bad start.from state: std::runtime_error,
// as `dem run` reports it); never another exception, a crash, a sanitizer report, a hang or an
// unbounded allocation. The disc limit is lowered to 20000 so that the fuzzer's memory and time
// limits measure the reader, not legitimately large scenes.
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "scene/scene.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"

namespace {

// A private directory with the scene and the companions a scene may name relatively:
// discs.csv (fill.file) and rested.state (start.from, a state of a 2-disc scene).
const std::string& work_dir() {
  static const std::string dir = [] {
    char tmpl[] = "/tmp/dem_fuzz_XXXXXX";
    if (!mkdtemp(tmpl)) {
      std::perror("mkdtemp");
      std::abort();
    }
    std::string d = tmpl;
    std::ofstream(d + "/discs.csv") << "id,x,y,r,vx,vy,omega,material\n0,10,5,1,0,0,0,sand\n1,12.5,5,1,0.5,0,0,sand\n";
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = work_dir() + "/scene.toml";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  dem::SceneOverrides ov;
  ov.max_discs = 20000;
  dem::SceneSpec spec;
  dem::World world;
  try {
    spec = dem::load_scene(path, ov);
    dem::build_world(spec, world);
  } catch (const dem::SceneError&) {
    return 0;  // refused with a message: the expected outcome for most inputs
  }
  if (!spec.start_from.empty()) {
    try {
      dem::load_state(world, spec.start_from);
    } catch (const std::runtime_error&) {
      return 0;
    }
  }
  for (int k = 0; k < 3; ++k) world.step();
  return 0;
}
