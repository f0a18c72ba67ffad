// The paper's silo filled to rest: global force balance and mirror symmetry; contact history
// across neighbour-list rebuilds.
#include <gtest/gtest.h>

#include <cmath>

#include "io/outputs.hpp"
#include "run/scene_run.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

using namespace dem;

namespace {
std::string scene_path(const char* name) { return std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/" + name; }

double side_total(const std::vector<WallLoad>& loads, const std::string& group) {
  double s = 0;
  for (const auto& L : loads) if (L.group == group) s += L.normal;
  return s;
}
}  // namespace

class StaticSilo : public ::testing::TestWithParam<const char*> {};

TEST_P(StaticSilo, WeightEqualsFloorForcePlusWallFrictionAndIsSymmetric) {
  SceneSpec spec = load_scene(scene_path(GetParam()));
  spec.rest_factor = 1e-7;  // stricter than the paper's note 3, so inertia is negligible
  spec.progress = false;
  World w;
  build_world(spec, w);
  ASSERT_EQ(run_fill(spec, w), Status::rest) << GetParam();

  std::vector<WallLoad> walls;
  std::vector<PointLoad> points;
  measure_loads(w, 2.0, walls, points);
  double weight = 0;
  for (std::size_t i = 0; i < w.discs.size(); ++i) weight += w.discs.mass(i) * 980.0;
  double floor = 0, friction = 0;
  for (const auto& L : walls) {
    if (L.group == "bottom") floor += -L.fy;               // discs push the floor down
    if (L.group.rfind("side", 0) == 0) friction += L.shear; // downward drag on the side walls
  }
  for (const auto& P : points) floor += -P.fy;
  EXPECT_NEAR(floor + friction, weight, 1e-6 * weight) << GetParam();

  // Mirror symmetry x -> W - x: left/right side-wall profiles and bottom pieces.
  const WallLoad *left = nullptr, *right = nullptr, *bl = nullptr, *br = nullptr;
  for (const auto& L : walls) {
    if (L.name == "left") left = &L;
    if (L.name == "right") right = &L;
    if (L.name == "bottom_left") bl = &L;
    if (L.name == "bottom_right") br = &L;
  }
  ASSERT_TRUE(left && right && bl && br);
  const double scale = 1e-6 * left->normal;
  ASSERT_GT(left->normal, 0);
  for (std::size_t b = 0; b < left->bin_normal.size(); ++b) {
    EXPECT_NEAR(left->bin_normal[b], right->bin_normal[b], scale) << "bin " << b;
    EXPECT_NEAR(left->bin_shear[b], right->bin_shear[b], scale) << "bin " << b;
  }
  EXPECT_NEAR(bl->normal, br->normal, 1e-6 * bl->normal);
  EXPECT_NEAR(bl->shear, -br->shear, 1e-6 * bl->normal);  // a -> b directions mirror
  EXPECT_NEAR(side_total(walls, "side_left"), side_total(walls, "side_right"), scale);
}

INSTANTIATE_TEST_SUITE_P(Paper, StaticSilo, ::testing::Values("silo_11_12.toml", "silo_17_18.toml"));

TEST(Neighbors, HistorySurvivesRebuildsBitForBit) {
  // The same fill with a tiny skin (many rebuilds) and a large one (few) must agree exactly:
  // lists are sorted, so the force sums run in the same order, and history is merged.
  SceneSpec spec = load_scene(scene_path("silo_17_18.toml"));
  spec.progress = false;
  spec.stop_at_rest = false;
  spec.end_time = 0.3;
  World a, b;
  spec.skin = 0.005;
  build_world(spec, a);
  spec.skin = 1.5;
  build_world(spec, b);
  run_fill(spec, a);
  run_fill(spec, b);
  EXPECT_GT(a.neighbors.rebuilds, 5 * b.neighbors.rebuilds);
  for (std::size_t i = 0; i < a.discs.size(); ++i) {
    ASSERT_EQ(a.discs.x[i], b.discs.x[i]) << "disc " << i;
    ASSERT_EQ(a.discs.y[i], b.discs.y[i]) << "disc " << i;
  }
}
