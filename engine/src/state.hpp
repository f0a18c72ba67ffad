// Saving and restoring a run's full state (positions, velocities, spins, last increments and
// forces, contact history, removed walls), so a run split in two continues bit-exactly.
#pragma once

#include <string>

#include "world.hpp"

namespace dem {

// Binary, this machine's byte order; the header names the format version.
void save_state(const World& w, const std::string& path);

// Restores into a world built from the same scene (geometry, materials, options); throws
// std::runtime_error naming the file and the reason when it does not fit.
void load_state(World& w, const std::string& path);

}  // namespace dem
