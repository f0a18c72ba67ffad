// The increments of a step (eqs. 5 and the rest measure of note 3) for every scheme: eq. (19)
// keeps its own arrays, eq. (18) and Verlet read v dt (World::increments). Whatever is stored,
// the rest measure must be the mean displacement of the step, which is measured here from the
// positions before and after it.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

World settling(const char* scheme, int threads) {
  SceneOverrides ov;
  ov.scheme = scheme;
  ov.dt = 5e-5;
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov);
  spec.threads = threads;
  World w;
  build_world(spec, w);
  for (int s = 0; s < 200; ++s) w.step();
  return w;
}

TEST(Increments, RestMeasureIsTheMeanDisplacementOfTheStep) {
  for (const char* scheme : {"paper_eq18", "paper_eq19", "velocity_verlet"}) {
    for (int threads : {1, 2}) {
      World w = settling(scheme, threads);
      EXPECT_EQ(w.discs.dux.empty(), w.scheme != Scheme::paper_eq19) << scheme << ": increment arrays only for eq. 19";
      const std::vector<double> x0 = w.discs.x, y0 = w.discs.y;
      w.measure_increments = true;
      w.step();
      double mx = 0, my = 0;
      w.mean_abs_increment(mx, my);
      double sx = 0, sy = 0;
      for (std::size_t i = 0; i < x0.size(); ++i) {
        sx += std::abs(w.discs.x[i] - x0[i]);
        sy += std::abs(w.discs.y[i] - y0[i]);
      }
      sx /= static_cast<double>(x0.size());
      sy /= static_cast<double>(x0.size());
      EXPECT_GT(my, 1e-7) << scheme << ": the discs must be moving";
      EXPECT_NEAR(mx, sx, 1e-9 * sy) << scheme << ", " << threads << " threads";
      EXPECT_NEAR(my, sy, 1e-9 * sy) << scheme << ", " << threads << " threads";
      if (w.scheme == Scheme::velocity_verlet) {  // its v is overwritten: unmeasured steps refuse
        w.measure_increments = false;
        w.step();
        EXPECT_THROW(w.mean_abs_increment(mx, my), std::logic_error);
      }
    }
  }
}

}  // namespace
}  // namespace dem
