#include "io/thermo.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "io/files.hpp"
#include "physics/world.hpp"

namespace dem {

void Thermo::sample(const World& w, const char* phase) {
  if (groups_.empty())  // the walls (a removed gate among them) are those of the scene at every resume
    for (const Wall& wl : w.geometry.walls)
      if (std::find(groups_.begin(), groups_.end(), wl.group) == groups_.end()) groups_.push_back(wl.group);
  if (text_.empty()) {
    std::ostringstream o;
    o << "t,step,phase,discs,kinetic_energy,contacts,wall_contacts,max_overlap";
    for (const std::string& g : groups_) o << ',' << g << "_normal," << g << "_shear";
    o << '\n';
    text_ = o.str();
  }
  // Disc-disc contacts carrying a compressive elastic force; obstacle contacts touching.
  long contacts = 0, wall_contacts = 0;
  for (const PairContact& c : w.neighbors.pairs) contacts += c.en > 0;
  std::vector<double> normal(groups_.size(), 0.0), shear(groups_.size(), 0.0);
  const int nw = static_cast<int>(w.geometry.walls.size());
  for (const WallContact& c : w.neighbors.walls) {
    if (!c.touching) continue;
    ++wall_contacts;
    if (c.k >= nw) continue;  // a point: in no wall group
    const Wall& wl = w.geometry.walls[c.k];
    // The discs' force on the wall (outputs.cpp, measure_loads): normal f_n, shear along from -> to.
    const double fx = c.fn * c.nx - c.fs * c.ny, fy = c.fn * c.ny + c.fs * c.nx;
    const double len = std::hypot(wl.bx - wl.ax, wl.by - wl.ay);
    const std::size_t g = static_cast<std::size_t>(
        std::find(groups_.begin(), groups_.end(), wl.group) - groups_.begin());
    if (g == groups_.size() || !(len > 0)) continue;
    normal[g] += c.fn;
    shear[g] += (fx * (wl.bx - wl.ax) + fy * (wl.by - wl.ay)) / len;
  }
  std::ostringstream o;
  o << time_text(on_step_grid(w.time, w.dt)) << ',' << w.steps << ',' << phase << ',' << w.discs.size() << ',' << digits17(w.kinetic_energy())
    << ',' << contacts << ',' << wall_contacts << ',' << digits17(w.max_overlap);
  for (std::size_t g = 0; g < groups_.size(); ++g) o << ',' << digits17(normal[g]) << ',' << digits17(shear[g]);
  o << '\n';
  text_ += o.str();
  last_step_ = w.steps;
}

}  // namespace dem
