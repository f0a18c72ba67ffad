// The last good state (last_good.hpp): kept in memory or in a file, it gives back every per-disc
// array bit for bit, survives a checkpoint round trip, and a discharge keeps its own (every
// kKeepEvery steps after opening, of the discs present then) instead of the fill's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "run/discharge.hpp"
#include "run/last_good.hpp"
#include "run/scene_run.hpp"
#include "scene/scene.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

const std::string kScene = std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/discharge_17_18.toml";

// Bit-for-bit equality of every per-disc array.
void expect_same(const Discs& a, const Discs& b) {
  std::ostringstream sa(std::ios::binary), sb(std::ios::binary);
  BinaryOut oa{sa}, ob{sb};
  write_discs(oa, a);
  write_discs(ob, b);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(sa.str() == sb.str()) << "the kept discs differ from the discs given";
}

TEST(LastGood, GivesBackEveryArrayFromMemoryFileAndCheckpoint) {
  SceneSpec spec = load_scene(kScene);
  World w;
  build_world(spec, w);
  for (int s = 0; s < 200; ++s) w.step();  // falling discs: every array non-trivial
  const Discs kept = w.discs;
  const std::string file = (std::filesystem::temp_directory_path() / "dem_test_last_good.bin").string();
  const std::string file2 = file + "2";
  for (const std::string& where : {std::string(), file}) {
    LastGood g;
    g.set_file(where);
    EXPECT_FALSE(g.has());
    g.keep(w.discs, w.time);
    EXPECT_EQ(g.time(), w.time);
    for (int s = 0; s < 50; ++s) w.step();  // the world moves on; the kept state does not
    expect_same(g.load(), kept);
    // A checkpoint carries it: written out, read back into another keeper (memory and file).
    std::stringstream ckpt(std::ios::in | std::ios::out | std::ios::binary);
    BinaryOut o{ckpt};
    g.write_to(o);
    for (const std::string& other : {std::string(), file2}) {
      ckpt.clear();
      ckpt.seekg(0);
      BinaryIn in{ckpt, "checkpoint"};
      LastGood back;
      back.set_file(other);
      back.read_from(in);
      ASSERT_TRUE(back.has());
      EXPECT_EQ(back.time(), g.time());
      expect_same(back.load(), kept);
      back.discard();
      EXPECT_FALSE(std::filesystem::exists(other)) << "discard removes the file";
    }
    g.discard();
    EXPECT_FALSE(g.has());
    if (!where.empty()) {
      EXPECT_FALSE(std::filesystem::exists(where));
      EXPECT_THROW(g.load(), std::logic_error);
    }
    w = World{};
    build_world(spec, w);
    for (int s = 0; s < 200; ++s) w.step();  // the same state again for the next keeper
  }
}

TEST(LastGood, DischargeKeepsItsOwnEveryThousandSteps) {
  SceneOverrides ov;
  ov.end_time = 0.3;  // a short fill: the discs still settle when the slit opens, they flow at once
  SceneSpec spec = load_scene(kScene, ov);
  spec.discharge.time = 0.25;  // 2500 steps of 1e-4 s: kept at 1000 and 2000
  spec.discharge.snapshots = {};
  World w;
  build_world(spec, w);
  const std::string out = (std::filesystem::temp_directory_path() / "dem_test_last_good_discharge").string();
  std::filesystem::create_directories(out);
  SceneRun run(spec, w, out);
  ASSERT_EQ(run.run(false, false), Status::discharged);
  const double t_open = run.discharge->st.t_open;
  ASSERT_NEAR(t_open, 0.3, 1e-9) << "the fill ends at its end time";
  ASSERT_GT(run.discharge->removals().size(), 0u) << "discs must leave during the kept interval";
  // Kept at the check of step 2000 after opening: its time, and the discs present then.
  EXPECT_NEAR(run.runner.last_good.time(), t_open + 2000 * w.dt, 0.5 * w.dt);
  const Discs good = run.runner.last_good.load();
  EXPECT_GE(good.size(), w.discs.size());
  EXPECT_LE(good.size(), 350u);
  for (std::size_t i = 0; i < good.size(); ++i) {
    ASSERT_TRUE(std::isfinite(good.x[i]) && std::isfinite(good.y[i]) && std::isfinite(good.vx[i]));
    if (i > 0) {
      ASSERT_LT(good.id_at(i - 1), good.id_at(i)) << "removals keep the order of ids";
    }
  }
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace dem
