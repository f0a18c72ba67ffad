// Saving and restoring a run's full state (positions, velocities, spins, last increments and
// forces, contact history, removed walls), so a run split in two continues bit-exactly.
#pragma once

#include <cstdint>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/world.hpp"

namespace dem {

// Binary, this machine's byte order; the header names the format version.
void save_state(const World& w, const std::string& path);

// Restores into a world built from the same scene (geometry, materials, options); throws
// std::runtime_error naming the file and the reason when it does not fit.
void load_state(World& w, const std::string& path);

// Binary streams shared by state files and checkpoints (checkpoint.hpp).
struct BinaryOut {
  std::ostream& out;
  template <class T> void put(const T& v) { out.write(reinterpret_cast<const char*>(&v), sizeof v); }
  template <class T> void vec(const std::vector<T>& v) {
    put<std::uint64_t>(v.size());
    out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
  }
  void str(const std::string& s) {
    put<std::uint64_t>(s.size());
    out.write(s.data(), static_cast<std::streamsize>(s.size()));
  }
};

struct BinaryIn {
  std::istream& in;
  std::string path;  // for messages
  [[noreturn]] void fail(const std::string& why) const { throw std::runtime_error(path + ": " + why); }
  template <class T> T get() {
    T v;
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) fail("truncated file");
    return v;
  }
  std::uint64_t count(std::uint64_t limit) {
    const auto n = get<std::uint64_t>();
    if (n > limit) fail("corrupt file (array of " + std::to_string(n) + " entries)");
    return n;
  }
  template <class T> void vec(std::vector<T>& v, std::uint64_t limit = 1ull << 32) {
    const auto n = count(limit);
    v.resize(n);
    if (!in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)))) fail("truncated file");
  }
  // The next n bytes to `out`, in blocks of 1 MB (a large blob without a copy in memory).
  void copy_to(std::ostream& out, std::uint64_t n) {
    std::string block;
    for (std::uint64_t left = n; left > 0;) {
      block.resize(static_cast<std::size_t>(left < (1u << 20) ? left : (1u << 20)));
      if (!in.read(block.data(), static_cast<std::streamsize>(block.size()))) fail("truncated file");
      out.write(block.data(), static_cast<std::streamsize>(block.size()));
      left -= block.size();
    }
  }
  std::string str(std::uint64_t limit = 1ull << 34) {
    std::string s(count(limit), '\0');
    if (!in.read(s.data(), static_cast<std::streamsize>(s.size()))) fail("truncated file");
    return s;
  }
};

// The world's state as in a state file, without the header: time, steps, dt, scheme, discs,
// wall flags, contact lists with their history.
void write_world(BinaryOut& o, const World& w);
// Every per-disc array (read checks they have one length).
void write_discs(BinaryOut& o, const Discs& d);
void read_discs(BinaryIn& r, Discs& d);
// Reads it into a world built from the same scene and checks that it fits; the caller then
// calls w.prepare() (state files) or restores the lists exactly (checkpoints).
void read_world(BinaryIn& r, World& w);

}  // namespace dem
