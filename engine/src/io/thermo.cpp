#include "io/thermo.hpp"

#include <algorithm>
#include <sstream>

#include "io/files.hpp"
#include "measures/group_loads.hpp"
#include "physics/world.hpp"

namespace dem {

const std::vector<std::string>& Thermo::groups(const World& w) {
  if (groups_.empty())  // the walls (a removed gate among them) are those of the scene at every resume
    for (const Wall& wl : w.geometry.walls)
      if (std::find(groups_.begin(), groups_.end(), wl.group) == groups_.end()) groups_.push_back(wl.group);
  return groups_;
}

void Thermo::sample(const World& w, const char* phase, const GroupLoads& loads) {
  groups(w);
  if (text_.empty()) {
    std::ostringstream o;
    o << "t,step,phase,discs,kinetic_energy,contacts,wall_contacts,max_overlap";
    for (const std::string& g : groups_) o << ',' << g << "_normal," << g << "_shear";
    o << '\n';
    text_ = o.str();
  }
  std::ostringstream o;
  o << time_text(on_step_grid(w.time, w.dt)) << ',' << w.steps << ',' << phase << ',' << w.discs.size() << ',' << digits17(w.kinetic_energy())
    << ',' << loads.contacts << ',' << loads.wall_contacts << ',' << digits17(w.max_overlap);
  for (std::size_t g = 0; g < groups_.size(); ++g) o << ',' << digits17(loads.normal[g]) << ',' << digits17(loads.shear[g]);
  o << '\n';
  text_ += o.str();
  last_step_ = w.steps;
}

}  // namespace dem
