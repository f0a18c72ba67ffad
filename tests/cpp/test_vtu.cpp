// VTU files (io/vtu.hpp): output.vtu's choice of binary, the walls' file, and the binary layout
// (each array's offset in the header points at its own block header).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "io/vtu.hpp"
#include "scene/scene_spec.hpp"

using namespace dem;

namespace {
std::string read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream o;
  o << in.rdbuf();
  return o.str();
}
}  // namespace

TEST(Vtu, AutoIsBinaryAbove10kDiscs) {
  SceneSpec s;
  EXPECT_FALSE(s.vtu_binary(10000));
  EXPECT_TRUE(s.vtu_binary(10001));
  s.vtu = VtuChoice::ascii;
  EXPECT_FALSE(s.vtu_binary(1'000'000));
  s.vtu = VtuChoice::binary;
  EXPECT_TRUE(s.vtu_binary(1));
}

TEST(Vtu, WallsFileHoldsTheActiveWallsAsLines) {
  Geometry g;
  g.walls.push_back({"left", "side", 0, 1, 0, 0, 0});
  g.walls.push_back({"gate", "bottom", 0, 0, 1, 0, 0});
  g.walls.push_back({"right", "side", 1, 1, 1, 0, 0});
  g.walls[1].active = false;
  const std::string path = (std::filesystem::temp_directory_path() / "dem_test_walls.vtu").string();
  write_walls_vtu(path, g, false);
  const std::string text = read(path);
  EXPECT_NE(text.find("NumberOfPoints=\"4\" NumberOfCells=\"2\""), std::string::npos) << text;
  EXPECT_NE(text.find("Name=\"wall\" format=\"ascii\">\n0\n2\n</DataArray>"), std::string::npos) << text;
  EXPECT_NE(text.find("Name=\"types\" format=\"ascii\">\n3\n3\n"), std::string::npos) << text;
  std::filesystem::remove(path);
}

TEST(Vtu, BinaryOffsetsPointAtEachArraysHeader) {
  VtuGrid g;
  g.np = 100000;  // several 32 kB blocks a column
  g.point = [](std::size_t i, double& x, double& y) { x = 0.5 * i; y = -1.0 * i; };
  g.scalars = {{"radius", [](std::size_t i) { return 1.0 + i % 7; }}};
  g.ints = {{"id", [](std::size_t i) { return static_cast<long long>(i); }}};
  std::ostringstream o;
  write_vtu(o, g, true);
  const std::string text = o.str();
  const std::size_t start = text.find("<AppendedData encoding=\"raw\">\n_");
  ASSERT_NE(start, std::string::npos);
  const std::size_t data = start + std::strlen("<AppendedData encoding=\"raw\">\n_");
  std::regex offset_re("offset=\"(\\d+)\"");
  std::vector<std::uint64_t> offsets;
  for (std::sregex_iterator m(text.begin(), text.begin() + start, offset_re), end; m != end; ++m)
    offsets.push_back(std::stoull((*m)[1]));
  ASSERT_EQ(offsets.size(), 6u);  // points, connectivity, offsets, types, radius, id
  const std::uint64_t raw_bytes[6] = {24 * 100000, 8 * 100000, 8 * 100000, 100000, 8 * 100000, 4 * 100000};
  std::uint64_t at = 0;
  for (int k = 0; k < 6; ++k) {
    ASSERT_EQ(offsets[k], at) << k;
    std::uint64_t head[3];
    std::memcpy(head, text.data() + data + at, sizeof head);
    if (!vtu_compressed()) {
      EXPECT_EQ(head[0], raw_bytes[k]);
      at += 8 + head[0];
      continue;
    }
    // Compressed: blocks, block size, partial last block, then each block's compressed size.
    EXPECT_EQ(head[0], (raw_bytes[k] + 32767) / 32768) << k;
    EXPECT_EQ(head[2], raw_bytes[k] % 32768) << k;
    std::uint64_t total = 0;
    for (std::uint64_t b = 0; b < head[0]; ++b) {
      std::uint64_t n;
      std::memcpy(&n, text.data() + data + at + 24 + 8 * b, sizeof n);
      total += n;
    }
    at += 8 * (3 + head[0]) + total;
  }
  EXPECT_EQ(text.substr(data + at), "\n</AppendedData>\n</VTKFile>\n");
}
