// The kernel list: every combination compiled, each its own code, so that a contact pays for no
// option and no feature its scene does not have (the skip rows of benchmarks/kernels.cpp), and the
// one way to select from it (row_of). Two kinds of row: the force rows (a law and a feature set:
// the stages of a force pass, the onset scheme's pass) and the move rows (the move of the discs,
// eqs. 16-19, as a step asks for it). The vector width of the law and of the move is chosen once,
// at start-up (World::vector_width). docs/architecture-kernels.md counts the bodies compiled.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "physics/model.hpp"

namespace dem {

// A law: the three options of model.hpp.
struct Law {
  NormalSpring normal_spring;
  NoTension no_tension;
  FrictionCap friction_cap;
};

// What a scene has besides its law. Without shear (every pair shear-free) or without dashpots (no
// pair has one) those terms are not computed; without bonds or moving walls their code is absent.
struct Features {
  LeverArm lever_arm;
  bool shear, dashpots, bonds, moving_walls;
};

// The laws compiled: the ten distinct combinations of the options. Under the overlap spring
// e_n = K_n x overlap is never negative for a touching contact (overlap >= 0, eq. 3), so the
// elastic no-tension rule never goes slack: NoTension::overlap and NoTension::elastic give the
// same operations on the same values, and such a scene runs the elastic row (law_compiled).
inline constexpr Law kLaws[] = {
    {NormalSpring::incremental, NoTension::elastic, FrictionCap::elastic},  // the paper's
    {NormalSpring::incremental, NoTension::elastic, FrictionCap::total},
    {NormalSpring::incremental, NoTension::total, FrictionCap::elastic},
    {NormalSpring::incremental, NoTension::total, FrictionCap::total},
    {NormalSpring::incremental, NoTension::overlap, FrictionCap::elastic},
    {NormalSpring::incremental, NoTension::overlap, FrictionCap::total},
    {NormalSpring::overlap, NoTension::elastic, FrictionCap::elastic},
    {NormalSpring::overlap, NoTension::elastic, FrictionCap::total},
    {NormalSpring::overlap, NoTension::total, FrictionCap::elastic},
    {NormalSpring::overlap, NoTension::total, FrictionCap::total},  // LIGGGHTS' and YADE's (compare/)
};

// The row of kLaws that computes a scene's law.
constexpr Law law_compiled(Law l) {
  if (l.normal_spring == NormalSpring::overlap && l.no_tension == NoTension::overlap) l.no_tension = NoTension::elastic;
  return l;
}

// The feature sets compiled with each law. Bonds and moving walls come with shear and dashpots
// (their scenes have both). The contact-point arm only with shear: without shear no arm is read,
// and such a scene runs the radius kernel.
inline constexpr Features kFeatures[] = {
    // lever arm              shear  dashpots bonds  moving walls
    {LeverArm::radius,        true,  true,    false, false},
    {LeverArm::radius,        true,  true,    true,  false},
    {LeverArm::radius,        true,  true,    false, true},
    {LeverArm::radius,        true,  true,    true,  true},
    {LeverArm::radius,        false, true,    false, false},
    {LeverArm::radius,        true,  false,   false, false},
    {LeverArm::radius,        false, false,   false, false},
    {LeverArm::contact_point, true,  true,    false, false},
    {LeverArm::contact_point, true,  true,    true,  false},
    {LeverArm::contact_point, true,  true,    false, true},
    {LeverArm::contact_point, true,  true,    true,  true},
    {LeverArm::contact_point, true,  false,   false, false},
};

// The force kernels: each law with each feature set, kLaws[k / kFeatureCount] with
// kFeatures[k % kFeatureCount] for kernel k.
inline constexpr std::size_t kLawCount = sizeof kLaws / sizeof kLaws[0];
inline constexpr std::size_t kFeatureCount = sizeof kFeatures / sizeof kFeatures[0];
inline constexpr std::size_t kKernelCount = kLawCount * kFeatureCount;

// Each force row runs the pair law on blocks of pairs at one of these vector widths (doubles a
// vector: SSE2, AVX2, AVX-512), and so does each move row. The same bits at every width.
inline constexpr int kVectorWidths[] = {2, 4, 8};

// A move of the discs (World::move_block): a kick alone (17) or with the drift of (18) or (19);
// reset: the forces, once read, set to the next pass's start (velocity Verlet's first half step);
// owed: the last step's closing half kick first; for one kind of disc or several; the rotation
// angle integrated or not; the skin/2 test or not.
enum class Drift { none, eq18, eq19 };
struct MoveKey {
  Drift drift;
  bool reset, owed, one_kind, angle, far_test;
};
constexpr bool operator==(const MoveKey& a, const MoveKey& b) {
  return a.drift == b.drift && a.reset == b.reset && a.owed == b.owed && a.one_kind == b.one_kind &&
         a.angle == b.angle && a.far_test == b.far_test;
}

// The moves compiled: what a step asks for. A kick alone moves nothing (no angle, no test); reset
// and owed come with the drift of (18) alone (velocity Verlet's first half step), owed with reset.
constexpr std::size_t kMoveCount = 34;
constexpr std::array<MoveKey, kMoveCount> move_keys() {
  std::array<MoveKey, kMoveCount> keys{};
  std::size_t k = 0;
  for (bool one : {false, true}) keys[k++] = {Drift::none, false, false, one, false, false};
  constexpr struct { Drift drift; bool reset, owed; } kDrifts[] = {
      {Drift::eq18, false, false}, {Drift::eq19, false, false}, {Drift::eq18, true, false}, {Drift::eq18, true, true}};
  for (const auto& m : kDrifts)
    for (bool one : {false, true})
      for (bool angle : {false, true})
        for (bool test : {false, true}) keys[k++] = {m.drift, m.reset, m.owed, one, angle, test};
  return keys;
}
inline constexpr std::array<MoveKey, kMoveCount> kMoves = move_keys();

struct KernelKey {
  Law law;
  Features features;
};
constexpr bool operator==(const Law& a, const Law& b) {
  return a.normal_spring == b.normal_spring && a.no_tension == b.no_tension && a.friction_cap == b.friction_cap;
}
constexpr bool operator==(const Features& a, const Features& b) {
  return a.lever_arm == b.lever_arm && a.shear == b.shear && a.dashpots == b.dashpots && a.bonds == b.bonds &&
         a.moving_walls == b.moving_walls;
}
constexpr bool operator==(const KernelKey& a, const KernelKey& b) { return a.law == b.law && a.features == b.features; }

// Force row k's key, as in the list.
constexpr KernelKey kernel_key(std::size_t k) { return {kLaws[k / kFeatureCount], kFeatures[k % kFeatureCount]}; }
constexpr std::array<KernelKey, kKernelCount> kernel_keys() {
  std::array<KernelKey, kKernelCount> keys{};
  for (std::size_t k = 0; k < kKernelCount; ++k) keys[k] = kernel_key(k);
  return keys;
}
inline constexpr std::array<KernelKey, kKernelCount> kKernels = kernel_keys();

// The one way to select: the row of `rows` with this key (rows.size() if none).
template <class Key, std::size_t N>
constexpr std::size_t row_of(const std::array<Key, N>& rows, const Key& key) {
  for (std::size_t k = 0; k < N; ++k)
    if (rows[k] == key) return k;
  return N;
}

// A force row's name: "normal_spring/no_tension/friction_cap arm[ shear][ dashpots][ bonds][ moving_walls]",
// e.g. "incremental/elastic/elastic radius shear dashpots" (the paper's law, every pair with both).
std::string kernel_name(const KernelKey& key);
// A move row's name: "move kick|eq18|eq19[ reset][ owed] one_kind|kinds[ angle][ far_test]".
std::string kernel_name(const MoveKey& key);

}  // namespace dem
