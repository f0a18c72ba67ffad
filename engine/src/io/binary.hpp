// Binary streams of state files, checkpoints and the last good state: this machine's byte
// order, every array with its length, every read checked (a short or corrupt file names itself).
#pragma once

#include <cstdint>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace dem {

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

}  // namespace dem
