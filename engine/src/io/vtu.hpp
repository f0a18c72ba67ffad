// VTK XML unstructured grids (.vtu) for ParaView and meshio, streamed from accessors: a 1M-disc
// file never sits in memory, as text or as copies of its columns. ASCII, or binary (raw appended
// data, zlib-compressed blocks when the build has zlib); docs/outputs.md.
#pragma once

#include <cstddef>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "physics/geometry.hpp"

namespace dem {

struct VtuColumn {
  std::string name;
  std::function<double(std::size_t)> at;
};
struct VtuVector {  // a vector in the plane, written with z = 0
  std::string name;
  std::function<void(std::size_t, double&, double&)> at;
};
struct VtuIntColumn {
  std::string name;
  std::function<long long(std::size_t)> at;
};

// np points (point(k, x, y)) in cells of points_per_cell consecutive points of VTK type vtk_type;
// the columns have one value a cell (cell_data) or a point.
struct VtuGrid {
  std::size_t np = 0;
  std::function<void(std::size_t, double&, double&)> point;
  int points_per_cell = 1, vtk_type = 1;
  std::vector<VtuColumn> scalars;
  std::vector<VtuVector> vectors;
  std::vector<VtuIntColumn> ints;
  bool cell_data = false;
};

// ASCII (text at full precision) or binary: raw appended data with UInt64 headers, each array
// in zlib-compressed blocks (vtkZLibDataCompressor) when the build has zlib; `o` can be
// any stream.
void write_vtu(std::ostream& o, const VtuGrid& g, bool binary);

// Whether binary VTU files are zlib-compressed in this build.
bool vtu_compressed();

// The active walls of a geometry as VTK_LINE cells (cell data: `wall`, the wall's index in
// summary.json's walls), written atomically to path.
void write_walls_vtu(const std::string& path, const Geometry& g, bool binary);

}  // namespace dem
