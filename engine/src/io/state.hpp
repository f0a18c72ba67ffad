// Saving and restoring a run's full state (positions, velocities, spins, last increments and
// forces, contact history, removed walls), so a run split in two continues bit-exactly.
#pragma once

#include <cstdint>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/binary.hpp"
#include "physics/world.hpp"

namespace dem {

// Binary, this machine's byte order; the header names the format version.
void save_state(const World& w, const std::string& path);

// Restores into a world built from the same scene (geometry, materials, options); throws
// std::runtime_error naming the file and the reason when it does not fit.
void load_state(World& w, const std::string& path);

// The world's state as in a state file, without the header: time, steps, dt, scheme, discs,
// wall flags, contact lists with their history (the onset scheme's kept f_n too).
void write_world(BinaryOut& o, const World& w);
// Every per-disc array (read checks they have one length).
void write_discs(BinaryOut& o, const Discs& d);
void read_discs(BinaryIn& r, Discs& d);
// Reads it into a world built from the same scene and checks that it fits; the caller then
// calls w.prepare() (state files) or restores the lists exactly (checkpoints). onset_normals:
// the file has World::onset_normals (false: a state file of version 6, which has none).
void read_world(BinaryIn& r, World& w, bool onset_normals = true);

}  // namespace dem
