// The arch over a silo's slit: the chain of compressive contacts that holds a jammed discharge.
#pragma once

#include <cstddef>
#include <vector>

namespace dem {

class World;

// What one find_arch call searched: the searches run (each in a wider disc around the slit than
// the last, the last over all records) and the records they read, summed.
struct ArchStats {
  int searches = 0;
  std::size_t records = 0;
};

// Disc indices of the arch over the slit: the shortest chain of touching discs from one slit end
// (point L or the bottom wall within 2 r of it) to the other, over the pairs with a compressive
// total force in this step's recorded pass. Empty when there is none.
std::vector<int> find_arch(const World& w, double slit_left, double slit_right, double floor_y,
                           ArchStats* stats = nullptr);

}  // namespace dem
