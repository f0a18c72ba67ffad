// Positions at opening (opening_positions.hpp): in memory or in a file read back block by block,
// every id gives the position its disc had, ids without a disc read NaN, in any reading order,
// and a checkpoint round trip keeps them.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "io/opening_positions.hpp"
#include "io/state.hpp"

namespace dem {
namespace {

// 150001 discs (more than two read blocks) with every 7th id removed: gaps inside the blocks (the
// last id stays).
constexpr int kIds = 150001;
Discs discs_with_gaps() {
  Discs d;
  for (int k = 0; k < kIds; ++k) d.add(0.25 * k, -1.5 * k + 0.125, 0.5, 2.65, 0);
  std::vector<int> keep;
  for (std::size_t i = 0; i < d.size(); ++i)
    if (d.id_at(i) % 7 != 3) keep.push_back(static_cast<int>(i));
  Discs out;
  for (int i : keep) {
        out.id.push_back(d.id_at(i));
    out.x.push_back(d.x[i]);
    out.y.push_back(d.y[i]);
  }
  out.kinds = d.kinds;
  return out;
}

void expect_positions(const OpeningPositions& p, const Discs& d) {
  ASSERT_EQ(p.size(), static_cast<std::uint64_t>(kIds));
  OpeningPositions::Reader forward(p);
  for (std::size_t i = 0; i < d.size(); ++i) {
    double x0, y0;
    forward.at(d.id_at(i), x0, y0);
    ASSERT_EQ(x0, d.x[i]) << "id " << d.id_at(i);
    ASSERT_EQ(y0, d.y[i]) << "id " << d.id_at(i);
  }
  OpeningPositions::Reader backward(p);  // any order works (a block at a time)
  for (int id = kIds - 1; id >= 0; id -= 997) {
    double x0, y0;
    backward.at(id, x0, y0);
    if (id % 7 == 3) {
      EXPECT_TRUE(std::isnan(x0) && std::isnan(y0)) << "id " << id << " has no disc";
    } else {
      EXPECT_EQ(x0, 0.25 * id);
      EXPECT_EQ(y0, -1.5 * id + 0.125);
    }
  }
  double x0, y0;
  EXPECT_THROW(backward.at(kIds, x0, y0), std::out_of_range);
}

TEST(OpeningPositions, ReadBackFromMemoryFileAndCheckpoint) {
  const Discs d = discs_with_gaps();
  const std::string file = (std::filesystem::temp_directory_path() / "dem_test_opening.bin").string();
  for (const std::string& where : {std::string(), file}) {
    OpeningPositions p;
    p.set_file(where);
    p.keep(d);
    expect_positions(p, d);
    if (!where.empty()) {
      EXPECT_EQ(std::filesystem::file_size(where), 16u + 16u * static_cast<std::uintmax_t>(kIds));
    }
    std::stringstream ckpt(std::ios::in | std::ios::out | std::ios::binary);
    BinaryOut o{ckpt};
    p.write_to(o);
    for (const std::string& other : {std::string(), file + "2"}) {
      ckpt.clear();
      ckpt.seekg(0);
      BinaryIn in{ckpt, "checkpoint"};
      OpeningPositions back;
      back.set_file(other);
      back.read_from(in);
      expect_positions(back, d);
      back.discard();
      EXPECT_EQ(back.size(), 0u);
      if (!other.empty()) {
        EXPECT_FALSE(std::filesystem::exists(other));
      }
    }
    p.discard();
  }
}

TEST(OpeningPositions, KeepsDiscsInCellOrderByIdAndRefusesRepeatedIds) {
  // Discs in the engine's cell order (World::resort_discs): ids 1, 0; each position under its id.
  Discs d;
  d.add(0, 0, 0.5, 1, 0);
  d.add(1, 0, 0.5, 1, 0);
  d.make_ids();
  std::swap(d.id[0], d.id[1]);
  OpeningPositions p;
  p.keep(d);
  OpeningPositions::Reader r(p);
  double x, y;
  r.at(0, x, y);
  EXPECT_EQ(x, 1.0);
  r.at(1, x, y);
  EXPECT_EQ(x, 0.0);
  d.id[1] = d.id[0];
  EXPECT_THROW(p.keep(d), std::logic_error);
}

}  // namespace
}  // namespace dem
