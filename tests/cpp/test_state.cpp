// A run split in two at any step, through a saved state, equals the run in one piece, bit for
// bit: during a discharge (gate open, discs removed at the outlet), for every scheme.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "run/scene_run.hpp"
#include "scene/scene.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"

using namespace dem;

namespace {
std::string scene_path() { return std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/discharge_17_18.toml"; }

void outlet_step(World& w) {
  w.step();
  RemovedDiscs out;
  for (std::size_t i = 0; i < w.discs.size(); ++i)
    if (w.discs.y[i] < -4.0) out.sorted.push_back(static_cast<int>(i));
  w.remove_discs(out);
}
}  // namespace

TEST(State, SplitRunThroughSavedStateIsBitIdentical) {
  for (const char* scheme : {"paper_eq18", "paper_eq19", "velocity_verlet"}) {
    SceneOverrides ov;
    ov.scheme = scheme;
    ov.dt = 5e-5;
    SceneSpec spec = load_scene(scene_path(), ov);
    World a;
    build_world(spec, a);
    run_fill(spec, a);  // fill to rest
    ASSERT_TRUE(a.deactivate_wall("gate"));
    const std::string path = ::testing::TempDir() + "/split.state";
    for (long split : {1L, 1234L}) {
      World b = a;  // the same rested world, opened
      World c = a;
      for (long s = 0; s < 3000; ++s) outlet_step(b);
      for (long s = 0; s < split; ++s) outlet_step(c);
      save_state(c, path);
      World d;
      build_world(spec, d);  // a fresh world of the same scene
      load_state(d, path);
      for (long s = split; s < 3000; ++s) outlet_step(d);
      ASSERT_EQ(b.discs.size(), d.discs.size()) << scheme << " split " << split;
      ASSERT_LT(b.discs.size(), a.discs.size()) << "no disc left: the test needs a flowing discharge";
      for (std::size_t i = 0; i < b.discs.size(); ++i) {
        ASSERT_EQ(b.discs.id_at(i), d.discs.id_at(i));
        ASSERT_EQ(b.discs.x[i], d.discs.x[i]) << scheme << " split " << split << " disc " << i;
        ASSERT_EQ(b.discs.y[i], d.discs.y[i]);
        ASSERT_EQ(b.discs.omega[i], d.discs.omega[i]);
      }
      EXPECT_EQ(b.time, d.time);
      EXPECT_EQ(b.steps, d.steps);
    }
    std::remove(path.c_str());
  }
}

// A state holds the recorded totals of its last pass (a state saved at a run's end writes its
// contacts again): the same records come back, with their (i, j), whatever form they had.
TEST(State, KeepsTheRecordedTotals) {
  SceneOverrides ov;
  ov.dt = 5e-5;
  SceneSpec spec = load_scene(scene_path(), ov);
  World a;
  build_world(spec, a);
  for (int s = 0; s < 2000; ++s) a.step();
  a.record_pair_forces = true;
  a.compute_forces_now();  // a pass over the current list: the totals' bound form
  a.pair_forces_step = a.steps;
  ASSERT_FALSE(a.pair_totals.detached());
  World b = a;
  b.pair_totals.detach(b.neighbors.pairs);
  const std::vector<PairForce> want = a.recorded_pairs();
  ASSERT_GT(want.size(), 100u) << "the discs must touch";
  const std::string path = ::testing::TempDir() + "/totals.state";
  for (const World* w : {&a, &b}) {
    save_state(*w, path);
    World d;
    build_world(spec, d);
    load_state(d, path);
    EXPECT_TRUE(d.pair_forces_current());
    EXPECT_TRUE(d.pair_totals.detached());
    const std::vector<PairForce> got = d.recorded_pairs();
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t k = 0; k < want.size(); ++k) {
      ASSERT_EQ(got[k].i, want[k].i);
      ASSERT_EQ(got[k].j, want[k].j);
      ASSERT_EQ(got[k].fn, want[k].fn);
      ASSERT_EQ(got[k].fs, want[k].fs);
    }
  }
  std::remove(path.c_str());
}

TEST(State, RefusesAStateOfAnotherScheme) {
  SceneSpec spec = load_scene(scene_path());
  World a;
  build_world(spec, a);
  const std::string path = ::testing::TempDir() + "/other.state";
  save_state(a, path);
  SceneOverrides ov;
  ov.scheme = "velocity_verlet";
  ov.force_dt = true;  // same dt, other scheme
  SceneSpec other = load_scene(scene_path(), ov);
  World b;
  build_world(other, b);
  EXPECT_THROW(load_state(b, path), std::runtime_error);
  std::remove(path.c_str());
}

// The same with 2 threads, on the 10k-disc lattice silo (its discs settle into contact at once):
// the resumed run rebuilds its lists at the restart, at another step than the run in one piece,
// and the eq. 18 / 19 drifts rebuild them at the end of a step, inside the threads' region.
TEST(State, SplitRunWithTwoThreadsIsBitIdentical) {
  const std::string scene = std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml";
  for (const char* scheme : {"paper_eq18", "paper_eq19", "velocity_verlet"}) {
    SceneOverrides ov;
    ov.scheme = scheme;
    ov.dt = 5e-5;  // under every scheme's bound for this packing
    SceneSpec spec = load_scene(scene, ov);
    spec.threads = 2;
    World b, c;
    build_world(spec, b);
    build_world(spec, c);
    ASSERT_EQ(b.threads_for(static_cast<int>(b.discs.size())), 2) << "the test needs 2 threads at work";
    const long steps = 700, split = 317;
    for (long s = 0; s < steps; ++s) b.step();
    for (long s = 0; s < split; ++s) c.step();
    const std::string path = ::testing::TempDir() + "/split2.state";
    save_state(c, path);
    World d;
    build_world(spec, d);
    load_state(d, path);
    std::remove(path.c_str());
    for (long s = split; s < steps; ++s) d.step();
    long touching = 0;
    for (const PairContact& p : b.neighbors.pairs) touching += p.en != 0;
    EXPECT_GT(touching, static_cast<long>(b.discs.size() / 2)) << scheme << ": the discs must be in contact";
    EXPECT_GT(b.neighbors.rebuilds, 2) << scheme << ": the run must rebuild its lists";
    ASSERT_EQ(b.discs.size(), d.discs.size());
    for (std::size_t i = 0; i < b.discs.size(); ++i) {
      ASSERT_EQ(b.discs.x[i], d.discs.x[i]) << scheme << " disc " << i;
      ASSERT_EQ(b.discs.y[i], d.discs.y[i]) << scheme << " disc " << i;
      ASSERT_EQ(b.discs.vx[i], d.discs.vx[i]) << scheme << " disc " << i;
      ASSERT_EQ(b.discs.omega[i], d.discs.omega[i]) << scheme << " disc " << i;
    }
  }
}

// Removed discs as a sorted list of indices (no map of all discs): each survivor's new index is
// its old one less the removed discs below it, the count a mask would give.
TEST(RemovedDiscs, NewIndexIsTheCountOfSurvivorsBelow) {
  std::vector<char> mask(1000, 0);
  RemovedDiscs r;
  for (int k = 0; k < 1000; ++k)
    if ((k * 7919) % 13 == 0 || k == 0 || k == 999) {
      mask[k] = 1;
      r.sorted.push_back(k);
    }
  int survivors = 0;
  for (int k = 0; k < 1000; ++k) {
    EXPECT_EQ(r.new_index(k), mask[k] ? -1 : survivors) << k;
    survivors += !mask[k];
  }
  World w;
  for (int k = 0; k < 10; ++k) w.discs.add(k, 0, 0.5, 1.0, 0);
  RemovedDiscs unsorted;
  unsorted.sorted = {3, 2};
  EXPECT_THROW(w.remove_discs(unsorted), std::logic_error);
  RemovedDiscs outside;
  outside.sorted = {10};
  EXPECT_THROW(w.remove_discs(outside), std::logic_error);
  EXPECT_EQ(w.discs.size(), 10u) << "a refused removal removes nothing";
}
