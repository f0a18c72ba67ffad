// Google Benchmark kernels: the contact-force pass, the cell/list rebuild and the
// integration pass on a settled 10k-disc lattice silo (reference_inputs/scenes/bench_silo_10k.toml,
// the paper's law and eq. 19, 300 steps after the start so the lattice is in contact), at 1 and 2
// threads; and the rows of the skip table: the same force pass with and without a feature
// (shear, dashpots, walls, bonds), each variant its own row of the kernel table (physics/
// kernels.hpp; the label names it), the pass that records the pair totals (an output step's)
// against the one that does not, and a scene of one disc kind
// (its constants in registers) against several (read through each disc's kind); and the pair
// law eight or four pairs a vector (AVX-512 or AVX2, the widest the processor has) against four
// (`four_law`) and two (SSE2, `narrow_law`).
// DEM_KERNELS_SCENE=out/speed/bench_silo_100k_settled.toml (made by speed.py --start settled)
// times them on a settled packing, where most candidate pairs touch.
//
//   cmake --build build --target dem_kernels && build/benchmarks/dem_kernels
//   DEM_KERNELS_SCENE=reference_inputs/scenes/bench_silo_100k.toml build/benchmarks/dem_kernels
//
// Counters: items = disc-disc candidate pairs (forces), discs (rebuild, integration).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "run/last_good.hpp"
#include "scene/scene.hpp"
#include "physics/world.hpp"

namespace {

using dem::World;

// The settled world, built once; each benchmark works on its own copy.
const World& settled() {
  static std::unique_ptr<World> w = [] {
    auto p = std::make_unique<World>();
    const char* other = std::getenv("DEM_KERNELS_SCENE");  // another scene, e.g. bench_silo_100k.toml
    dem::SceneSpec spec = dem::load_scene(other ? std::string(other)
                                                : std::string(DEM_SOURCE_DIR) + "/reference_inputs/scenes/bench_silo_10k.toml");
    dem::build_world(spec, *p);
    for (int s = 0; s < 300; ++s) p->step();
    return p;
  }();
  return *w;
}

enum Variant { full, no_dashpots, no_shear, no_shear_no_dashpots, no_walls, with_bond, recorded, several_kinds, narrow_law,
               four_law };

World variant(Variant v, int threads) {
  World w = settled();
  w.threads = threads;
  for (dem::PairProps& p : w.props) {
    if (v == no_dashpots || v == no_shear_no_dashpots) p.eta_n = p.eta_s = 0;
    if (v == no_shear || v == no_shear_no_dashpots) p.ks = p.eta_s = 0;
  }
  if (v == no_walls) {  // the walls' entries removed from the lists: no disc-wall work at all
    w.geometry.walls.clear();
    w.geometry.points.clear();
  }
  if (v == with_bond) {  // one bond between the two first discs: the bond loop is compiled in
    dem::Bond b;
    b.i = 0;
    b.j = 1;
    b.ai = w.discs.r(0);
    b.aj = w.discs.r(1);
    b.rest = w.discs.r(0) + w.discs.r(1);
    w.bonds.push_back(b);
  }
  if (v == several_kinds) {  // a second kind that no disc has: the general path, through each disc's kind
    dem::DiscKinds& k = w.discs.kinds;
    k.r.push_back(2.0); k.mass.push_back(1.0); k.inv_mass.push_back(1.0); k.inv_inertia.push_back(1.0);
    k.material.push_back(0);
  }
  w.prepare();  // picks the kernel for the variant and rebuilds the lists
  w.record_pair_forces = v == recorded;  // the pass of an output step: it keeps f_n, f_s of the touching pairs
  return w;
}

void BM_ContactForces(benchmark::State& st) {
  World w = variant(static_cast<Variant>(st.range(0)), static_cast<int>(st.range(1)));
  // The law two pairs a vector (SSE2) or four (AVX2), or the widest the processor has.
  const int widest = World::vector_width;
  const int width = st.range(0) == narrow_law ? 2 : st.range(0) == four_law ? std::min(4, widest) : widest;
  w.set_vector_width(width);
  for (auto _ : st) {
    w.compute_forces_now();
    benchmark::DoNotOptimize(w.discs.fx.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.neighbors.pairs.size()));
  st.counters["pairs"] = static_cast<double>(w.neighbors.pairs.size());
  static const char* names[] = {"full", "no_dashpots", "no_shear", "no_shear_no_dashpots", "no_walls", "with_bond",
                                "recorded", "several_kinds", "narrow_law", "four_law"};
  st.SetLabel(std::string(names[st.range(0)]) + " [" + std::to_string(width) + " a vector] [kernel " + w.kernel_name() +
              "]");
}
BENCHMARK(BM_ContactForces)
    ->ArgsProduct({{full, no_dashpots, no_shear, no_shear_no_dashpots, no_walls, with_bond, recorded, several_kinds,
                    narrow_law, four_law},
                   {1}})
    ->ArgsProduct({{full}, {2}})
    ->Unit(benchmark::kMicrosecond);

void BM_CellRebuild(benchmark::State& st) {
  World w = variant(full, static_cast<int>(st.range(0)));
  for (auto _ : st) {
    w.neighbors.rebuild(w.discs, w.geometry, static_cast<int>(st.range(0)));
    benchmark::DoNotOptimize(w.neighbors.pairs.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.discs.size()));
}
BENCHMARK(BM_CellRebuild)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// Eq. (17) kick and the drift of every disc, one pass: eq. (19) (range 0 = 19), which stores its
// increments, or eq. (18) (18), whose increments are v dt and not stored (the skip row); one kind
// of disc (range 2 = 1) or several (2).
void BM_Integration(benchmark::State& st) {
  World w = variant(st.range(2) == 1 ? full : several_kinds, static_cast<int>(st.range(1)));
  w.compute_forces_now();  // a pass picks the one-kind path or not
  const bool eq19 = st.range(0) == 19;
  for (auto _ : st) {
    if (eq19) w.kick_drift_eq19(w.dt);
    else w.kick_drift_eq18(w.dt);
    benchmark::DoNotOptimize(w.discs.x.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.discs.size()));
  st.SetLabel(std::string(eq19 ? "eq. 19 (stores du)" : "eq. 18 (du = v dt, not stored)") +
              (st.range(2) == 1 ? ", one kind" : ", several kinds"));
}
BENCHMARK(BM_Integration)->ArgsProduct({{19, 18}, {1, 2}, {1, 2}})->Unit(benchmark::kMicrosecond);

// The same pass (eq. 19, 1 thread) keeping the rotation angle phi (output.rotation_angle, range 1)
// or not (0): the skip row of the angle, an output the law never reads.
void BM_IntegrationRotationAngle(benchmark::State& st) {
  World w = settled();
  w.threads = 1;
  w.rotation_angle = st.range(0) == 1;
  w.prepare();
  w.compute_forces_now();
  for (auto _ : st) {
    w.kick_drift_eq19(w.dt);
    benchmark::DoNotOptimize(w.discs.x.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.discs.size()));
  st.SetLabel(w.discs.phi.empty() ? "no angle" : "angle kept");
}
BENCHMARK(BM_IntegrationRotationAngle)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// Keeping the last good state (last_good.hpp) in a file, as runs do every 1000 steps instead of
// holding a copy in memory: every per-disc array written and renamed into place.
void BM_KeepLastGood(benchmark::State& st) {
  World w = variant(full, 1);
  dem::LastGood good;
  good.set_file((std::filesystem::temp_directory_path() / "dem_kernels_last_good.bin").string());
  for (auto _ : st) good.keep(w.discs, w.time);
  good.discard();
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.discs.size()));
}
BENCHMARK(BM_KeepLastGood)->Unit(benchmark::kMicrosecond);

void BM_Step(benchmark::State& st) {  // the whole step, for scale
  World w = variant(full, static_cast<int>(st.range(0)));
  const long r0 = w.neighbors.rebuilds;
  for (auto _ : st) w.step();
  st.SetItemsProcessed(st.iterations() * static_cast<long>(w.discs.size()));
  st.counters["steps_per_rebuild"] =
      static_cast<double>(st.iterations()) / static_cast<double>(std::max(1L, w.neighbors.rebuilds - r0));
}
BENCHMARK(BM_Step)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
