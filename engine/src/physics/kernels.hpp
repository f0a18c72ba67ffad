// The kernels compiled: every combination of the law and of the features a scene may use, each
// its own code, so that a contact pays for no option and no feature its scene does not have (the
// skip rows of benchmarks/kernels.cpp). World::select_kernel is the one dispatcher: it takes the
// row of this table that matches the scene. The vector width of the law and of the move is
// chosen once, at start-up (World::vector_width).
#pragma once

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

// The laws compiled: all twelve combinations of the options.
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
    {NormalSpring::overlap, NoTension::overlap, FrictionCap::elastic},
    {NormalSpring::overlap, NoTension::overlap, FrictionCap::total},
};

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

// Each force kernel runs the pair law on blocks of pairs at one of these vector widths (doubles a
// vector: SSE2, AVX2, AVX-512), and so does the move of the discs (eqs. 16-19), compiled for a
// kick alone or with the drift of (18) or (19), for one kind of disc or several, with the
// rotation angle or without, with the skin/2 test or without. The same bits at every width.
inline constexpr int kVectorWidths[] = {2, 4, 8};

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

// kernel k's key, as in the table.
constexpr KernelKey kernel_key(std::size_t k) { return {kLaws[k / kFeatureCount], kFeatures[k % kFeatureCount]}; }

// A kernel's name: "normal_spring/no_tension/friction_cap arm[ shear][ dashpots][ bonds][ moving_walls]",
// e.g. "incremental/elastic/elastic radius shear dashpots" (the paper's law, every pair with both).
std::string kernel_name(const KernelKey& key);

}  // namespace dem
