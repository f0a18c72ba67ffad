// The discs' loads on each group of walls, with the contacts counted beside them: thermo.csv's
// columns at a row's step.
#pragma once

#include <string>
#include <vector>

namespace dem {

class World;

struct GroupLoads {
  long contacts = 0;       // disc-disc contacts carrying a compressive elastic force
  long wall_contacts = 0;  // obstacle contacts touching
  std::vector<double> normal, shear;  // per group, in the order of `groups`
};

// The groups' normal and shear totals (shear along each wall from -> to); points are in no group.
GroupLoads measure_group_loads(const World& w, const std::vector<std::string>& groups);

}  // namespace dem
