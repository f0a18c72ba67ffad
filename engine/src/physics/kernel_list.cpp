// The kernel list (kernels.hpp): its force rows compiled, and the one dispatcher.
#include <stdexcept>
#include <utility>

#include "physics/contact_stages.hpp"
#include "physics/kernels.hpp"
#include "physics/onset_stage.hpp"
#include "physics/pair_law.hpp"
#include "physics/world.hpp"

namespace dem {

// Force row K of the kernel list (kernels.hpp): the stages of its law and features, its pair law
// at each vector width, its law on one contact, and (overlap spring, no bonds or moving walls)
// the onset scheme's pass. A stage depends only on what it reads: the pair stages on the arm,
// shear and the pass (the law is a call on a block of pairs), the wall stage on the arm, shear
// and moving walls; rows that share those share their code.
template <std::size_t K>
World::Kernel World::make_kernel() {
  constexpr KernelKey key = kernel_key(K);
  constexpr NormalSpring NS = key.law.normal_spring;
  constexpr NoTension NT = key.law.no_tension;
  constexpr FrictionCap FC = key.law.friction_cap;
  constexpr LeverArm LA = key.features.lever_arm;
  constexpr bool S = key.features.shear, D = key.features.dashpots, M = key.features.moving_walls;
  Kernel k;
  k.key = key;
  k.name = dem::kernel_name(key);
  k.pairs[0][0] = &World::pair_contacts<LA, S, false, false>;
  k.pairs[0][1] = &World::pair_contacts<LA, S, false, true>;
  k.pairs[1][0] = &World::pair_contacts<LA, S, true, false>;
  k.pairs[1][1] = &World::pair_contacts<LA, S, true, true>;
  k.cross[0] = &World::pair_contacts<LA, S, false, false, true>;
  k.cross[1] = &World::pair_contacts<LA, S, false, true, true>;
  k.walls = &World::wall_contacts<LA, M, S>;
  if constexpr (key.features.bonds) k.bonds = &World::bond_contacts<NS>;
  k.pair_law[0][0] = pair_block_law_at<2, NS, NT, FC, LA, S, D, false>();
  k.pair_law[0][1] = pair_block_law_at<2, NS, NT, FC, LA, S, D, true>();
  k.pair_law[1][0] = pair_block_law_at<4, NS, NT, FC, LA, S, D, false>();
  k.pair_law[1][1] = pair_block_law_at<4, NS, NT, FC, LA, S, D, true>();
  k.pair_law[2][0] = pair_block_law_at<8, NS, NT, FC, LA, S, D, false>();
  k.pair_law[2][1] = pair_block_law_at<8, NS, NT, FC, LA, S, D, true>();
  k.contact_law = &contact_law<NS, NT, FC, S, D>;
  if constexpr (NS == NormalSpring::overlap && !key.features.bonds && !key.features.moving_walls)
    k.onset = &World::onset_forces_law<NT, FC, LA>;
  return k;
}

namespace {
template <class Kernel, class Make, std::size_t... K>
std::vector<Kernel> make_table(Make make, std::index_sequence<K...>) {
  return {make(std::integral_constant<std::size_t, K>{})...};
}
}  // namespace

const std::vector<World::Kernel>& World::kernels() {
  static const std::vector<Kernel> table = make_table<Kernel>(
      [](auto k) { return make_kernel<decltype(k)::value>(); }, std::make_index_sequence<kKernelCount>{});
  return table;
}

std::vector<std::string> World::kernel_names() {
  std::vector<std::string> names;
  for (const Kernel& k : kernels()) names.push_back(k.name);
  for (const MoveKey& m : kMoves) names.push_back(dem::kernel_name(m));
  return names;
}

const std::string& World::kernel_name() const {
  static const std::string none = "none (prepare() selects it)";
  return kernel_ ? kernel_->name : none;
}

std::string kernel_name(const KernelKey& key) {
  const Law& l = key.law;
  const Features& f = key.features;
  std::string s = std::string(to_string(l.normal_spring)) + "/" + to_string(l.no_tension) + "/" + to_string(l.friction_cap) +
                  " " + to_string(f.lever_arm);
  if (f.shear) s += " shear";
  if (f.dashpots) s += " dashpots";
  if (f.bonds) s += " bonds";
  if (f.moving_walls) s += " moving_walls";
  return s;
}

std::string kernel_name(const MoveKey& key) {
  std::string s = std::string("move ") + (key.drift == Drift::none ? "kick" : key.drift == Drift::eq18 ? "eq18" : "eq19");
  if (key.reset) s += " reset";
  if (key.owed) s += " owed";
  s += key.one_kind ? " one_kind" : " kinds";
  if (key.angle) s += " angle";
  if (key.far_test) s += " far_test";
  return s;
}

// The one dispatcher: the force row for this scene's law and what it uses.
void World::select_kernel() {
  const bool has_bonds = !bonds.empty(), has_moving = !moving.empty();
  bool shear = false, dash = false;
  for (const PairProps& p : props) {
    const bool shear_free = (p.ks == 0 && p.eta_s == 0) || (p.mu == 0 && p.ks > 0);  // cap 0 holds e_s = 0
    shear = shear || !shear_free;
    dash = dash || p.eta_n != 0 || p.eta_s != 0;
  }
  if (has_bonds || has_moving) shear = dash = true;  // as the list compiles them
  kernel_shear = shear;
  kernel_dashpots = dash;
  // The lever arm matters only where there is shear: a shear-free scene runs the radius kernel
  // (the same result).
  const LeverArm lever = shear ? options.lever_arm : LeverArm::radius;
  const KernelKey want{law_compiled({options.normal_spring, options.no_tension, options.friction_cap}),
                       {lever, shear, dash, has_bonds, has_moving}};
  const std::size_t row = row_of(kKernels, want);
  if (row == kKernelCount) throw std::logic_error("no compiled kernel for " + dem::kernel_name(want));
  kernel_ = &kernels()[row];
}

}  // namespace dem
