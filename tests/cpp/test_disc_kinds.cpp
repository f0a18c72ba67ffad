// Disc kinds (discs.hpp): discs with the same radius, density and material share one entry of
// constants, any difference makes a new one, and the constants are those of the paper's disc
// (m = rho pi r^2, I = m r^2 / 2) whatever the order of adding. The kernels' path for a scene of
// one kind (constants kept in registers) gives the same bits as the general path.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "physics/discs.hpp"
#include "scene/scene.hpp"
#include "io/state.hpp"
#include "physics/world.hpp"

namespace dem {
namespace {

TEST(DiscKinds, SharedByEqualConstantsOnly) {
  Discs d;
  const double radii[3] = {0.5, 0.4, 0.5 + 1e-15};
  for (int k = 0; k < 3000; ++k) d.add(k, 0, radii[k % 3], k % 2 ? 2.65 : 1.0, k % 5 == 0 ? 1 : 0);
  // 3 radii x 2 densities x 2 materials, all combinations met.
  EXPECT_EQ(d.kinds.size(), 12u);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const int k = static_cast<int>(i);
    const double r = radii[k % 3], rho = k % 2 ? 2.65 : 1.0;
    const double m = rho * M_PI * r * r;
    ASSERT_EQ(d.r(i), r);
    ASSERT_DOUBLE_EQ(d.mass(i), m);
    ASSERT_DOUBLE_EQ(d.inv_mass(i), 1 / m);
    ASSERT_DOUBLE_EQ(d.inv_inertia(i), 1 / (0.5 * m * r * r));
    ASSERT_EQ(d.material(i), k % 5 == 0 ? 1 : 0);
  }
  // Every disc its own radius: one kind each.
  Discs poly;
  for (int k = 0; k < 5000; ++k) poly.add(k, 0, 0.3 + 1e-4 * k, 2.65, 0);
  EXPECT_EQ(poly.kinds.size(), 5000u);
  for (std::size_t i = 0; i < poly.size(); ++i) ASSERT_EQ(poly.r(i), 0.3 + 1e-4 * static_cast<double>(i));
  // The index may be dropped and rebuilt: later discs still find their kinds.
  poly.forget_kind_index();
  poly.add(0, 1, 0.3, 2.65, 0);
  EXPECT_EQ(poly.kinds.size(), 5000u);
  EXPECT_EQ(poly.kind.back(), poly.kind.front());
}

// Discs with an array left out and the same discs with it written out give the same bytes (the
// state format does not change); what is read back.
Discs written_alike_and_read_back(const Discs& implicit, const Discs& explicit_arrays) {
  std::ostringstream a, b;
  BinaryOut oa{a}, ob{b};
  write_discs(oa, implicit);
  write_discs(ob, explicit_arrays);
  EXPECT_EQ(a.str(), b.str()) << "an array left out is written as the values it stands for";
  std::istringstream in(b.str());
  BinaryIn r{in, "test"};
  Discs back;
  read_discs(r, back);
  return back;
}

// One kind: no kind array (a scene of one kind pays nothing for several); it appears, all zeros
// but the new disc's, when a second kind does, and the state files hold the same bytes either way.
TEST(DiscKinds, OneKindHasNoKindArrayUntilASecondKindComes) {
  Discs d;
  d.reserve(10000);
  for (int k = 0; k < 9000; ++k) d.add(k, 0, 0.5, 2.65, 0);
  EXPECT_TRUE(d.kind.empty());
  EXPECT_EQ(d.size(), 9000u);
  EXPECT_EQ(d.r(8999), 0.5);
  Discs full = d;  // the same discs written with an explicit array of zeros
  full.kind.assign(full.size(), 0);
  const Discs back = written_alike_and_read_back(d, full);
  EXPECT_TRUE(back.kind.empty()) << "read back with one kind: no array";
  EXPECT_EQ(back.size(), 9000u);
  // A second kind, at the end and in the middle.
  d.add(0, 1, 0.25, 2.65, 0);
  ASSERT_EQ(d.kind.size(), 9001u);
  EXPECT_GE(d.kind.capacity(), 10000u) << "made with the room reserve() asked for";
  EXPECT_EQ(d.kind.back(), 1);
  EXPECT_EQ(d.r(9000), 0.25);
  for (std::size_t i = 0; i < 9000; ++i) ASSERT_EQ(d.kind[i], 0);
  Discs pos;  // positions only (the scene's check of its discs): the same room for the kinds
  pos.reserve_positions(5000);
  for (int k = 0; k < 5000; ++k) pos.add_position(k, 0, k < 10 ? 0.5 : 0.25, 1.0, 0);
  ASSERT_EQ(pos.kind.size(), 5000u);
  EXPECT_EQ(pos.kind.capacity(), 5000u) << "no doubling slack";
  EXPECT_EQ(pos.r(9), 0.5);
  EXPECT_EQ(pos.r(10), 0.25);
  Discs h = back;
  h.hold(4321);
  ASSERT_EQ(h.kind.size(), 9000u);
  EXPECT_EQ(h.inv_mass(4321), 0.0);
  EXPECT_GT(h.inv_mass(4320), 0.0);
  EXPECT_GT(h.inv_mass(4322), 0.0);
}

// Ids: no array while they are the indices; the first removal makes it, and the state files
// hold the same bytes either way.
TEST(DiscIds, NoIdArrayUntilADiscLeaves) {
  SceneOverrides ov;
  SceneSpec spec = load_scene(std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml", ov);
  World w;
  build_world(spec, w);
  const std::size_t n = w.discs.size();
  ASSERT_GT(n, 1000u);
  EXPECT_TRUE(w.discs.id.empty());
  EXPECT_EQ(w.discs.id_at(n - 1), static_cast<int>(n - 1));
  Discs full = w.discs;
  full.make_ids();
  ASSERT_EQ(full.id.size(), n);
  const Discs back = written_alike_and_read_back(w.discs, full);
  EXPECT_TRUE(back.id.empty()) << "ids that are the indices are read back as none";
  const double x_after = w.discs.x[8];
  RemovedDiscs gone;
  gone.sorted = {0, 5, 6};
  w.remove_discs(gone);
  ASSERT_EQ(w.discs.id.size(), n - 3);
  EXPECT_EQ(w.discs.id_at(0), 1);
  EXPECT_EQ(w.discs.id_at(4), 7);
  EXPECT_EQ(w.discs.id_at(5), 8);
  EXPECT_EQ(w.discs.x[5], x_after);
  EXPECT_EQ(w.discs.id_at(n - 4), static_cast<int>(n - 1));
}

TEST(DiscKinds, HoldGivesOneDiscItsOwnKind) {
  Discs d;
  for (int k = 0; k < 4; ++k) d.add(k, 0, 0.5, 2.65, 0);
  d.hold(2);
  EXPECT_EQ(d.kinds.size(), 2u);
  EXPECT_EQ(d.inv_mass(2), 0.0);
  EXPECT_EQ(d.inv_inertia(2), 0.0);
  EXPECT_EQ(d.r(2), 0.5);
  EXPECT_EQ(d.mass(2), d.mass(1));
  EXPECT_GT(d.inv_mass(1), 0.0);
}

TEST(DiscKinds, OneKindPathGivesTheBitsOfTheGeneralPath) {
  SceneOverrides ov;
  ov.scheme = "velocity_verlet";
  ov.dt = 5e-5;
  const std::string scene = std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml";
  for (const char* scheme : {"velocity_verlet", "paper_eq19"}) {
    ov.scheme = scheme;
    ov.dt = std::string(scheme) == "paper_eq19" ? 1e-4 : 5e-5;
    ov.force_dt = true;
    for (int threads : {1, 2}) {
      SceneSpec spec = load_scene(scene, ov);
      spec.threads = threads;
      World one, general;
      build_world(spec, one);
      build_world(spec, general);
      ASSERT_EQ(one.discs.kinds.size(), 1u) << "the lattice silo has one kind of disc";
      // A second kind that no disc has: the kernels take the general path, reading each disc's kind.
      DiscKinds& k = general.discs.kinds;
      k.r.push_back(2.0); k.mass.push_back(1.0); k.inv_mass.push_back(1.0); k.inv_inertia.push_back(1.0);
      k.material.push_back(0);
      general.discs.kind.assign(general.discs.size(), 0);  // with two kinds the array is there (Discs::kind)
      ASSERT_TRUE(one.discs.kind.empty()) << "one kind: no kind array";
      one.record_pair_forces = general.record_pair_forces = true;
      for (int s = 0; s < 400; ++s) {
        one.step();
        general.step();
      }
      ASSERT_GT(one.pair_totals.size(), 1000u) << "the discs touch";
      for (std::size_t i = 0; i < one.discs.size(); ++i) {
        ASSERT_EQ(one.discs.x[i], general.discs.x[i]) << scheme << ", " << threads << " threads, disc " << i;
        ASSERT_EQ(one.discs.y[i], general.discs.y[i]);
        ASSERT_EQ(one.discs.vx[i], general.discs.vx[i]);
        ASSERT_EQ(one.discs.omega[i], general.discs.omega[i]);
        ASSERT_EQ(one.discs.fy[i], general.discs.fy[i]);
      }
      const std::vector<PairForce> a = one.recorded_pairs(), b = general.recorded_pairs();
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t p = 0; p < a.size(); ++p) ASSERT_EQ(a[p].fn, b[p].fn);
    }
  }
}

}  // namespace
}  // namespace dem
