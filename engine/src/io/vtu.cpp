#include "io/vtu.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "io/files.hpp"

#ifdef DEM_HAVE_ZLIB
#include <zlib.h>
#endif

namespace dem {

namespace {

void ascii(std::ostream& o, const VtuGrid& g) {
  const std::size_t np = g.np, nc = np / g.points_per_cell, nv = g.cell_data ? nc : np;
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << np << "\" NumberOfCells=\"" << nc << "\">\n";
  o << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < np; ++i) {
    double x, y;
    g.point(i, x, y);
    o << digits17(x) << ' ' << digits17(y) << " 0\n";
  }
  o << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < np; ++i) o << i << '\n';
  o << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < nc; ++c) o << (c + 1) * g.points_per_cell << '\n';
  o << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < nc; ++c) o << g.vtk_type << '\n';
  o << "</DataArray>\n</Cells>\n";
  o << (g.cell_data ? "<CellData>\n" : "<PointData>\n");
  for (const VtuColumn& c : g.scalars) {
    o << "<DataArray type=\"Float64\" Name=\"" << c.name << "\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < nv; ++i) o << digits17(c.at(i)) << '\n';
    o << "</DataArray>\n";
  }
  for (const VtuVector& c : g.vectors) {
    o << "<DataArray type=\"Float64\" Name=\"" << c.name << "\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < nv; ++i) {
      double x, y;
      c.at(i, x, y);
      o << digits17(x) << ' ' << digits17(y) << " 0\n";
    }
    o << "</DataArray>\n";
  }
  for (const VtuIntColumn& c : g.ints) {
    o << "<DataArray type=\"Int32\" Name=\"" << c.name << "\" format=\"ascii\">\n";
    for (std::size_t i = 0; i < nv; ++i) o << c.at(i) << '\n';
    o << "</DataArray>\n";
  }
  o << (g.cell_data ? "</CellData>\n" : "</PointData>\n") << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
}

// One array of the appended data: its VTK type and components, its byte count, and a writer of
// its bytes in order (called once to measure compressed sizes, once to write).
using Put = std::function<void(const void*, std::size_t)>;
struct Array {
  std::string type, name;
  int components = 1;
  std::uint64_t bytes = 0;
  std::function<void(const Put&)> emit;
};

constexpr std::size_t kBlock = 1 << 15;  // VTK's default block of a compressed array

// Cuts an array's bytes into kBlock blocks and hands each (compressed when zlib is used) to `sink`.
class Blocks {
 public:
  Blocks(bool z, std::function<void(const char*, std::size_t)> sink) : z_(z), sink_(std::move(sink)) {
    buf_.reserve(kBlock);
  }
  void put(const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    while (n > 0) {
      const std::size_t k = std::min(n, kBlock - buf_.size());
      buf_.insert(buf_.end(), c, c + k);
      c += k;
      n -= k;
      if (buf_.size() == kBlock) flush();
    }
  }
  void finish() {
    if (!buf_.empty()) flush();
  }

 private:
  void flush() {
#ifdef DEM_HAVE_ZLIB
    if (z_) {
      uLongf size = compressBound(static_cast<uLong>(buf_.size()));
      packed_.resize(size);
      // Level 1: the fastest; the columns of doubles compress little at any level.
      if (compress2(reinterpret_cast<Bytef*>(packed_.data()), &size, reinterpret_cast<const Bytef*>(buf_.data()),
                    static_cast<uLong>(buf_.size()), 1) != Z_OK)
        throw std::runtime_error("zlib could not compress a VTU block");
      sink_(packed_.data(), size);
      buf_.clear();
      return;
    }
#endif
    sink_(buf_.data(), buf_.size());
    buf_.clear();
  }
  bool z_;
  std::function<void(const char*, std::size_t)> sink_;
  std::vector<char> buf_, packed_;
};

template <class T>
void put_value(const Put& put, T v) {
  put(&v, sizeof v);
}

// The grid's arrays, in the file's order: the points, the cells, the data.
struct Arrays {
  std::vector<Array> points, cells, data;
};

Arrays grid_arrays(const VtuGrid& g) {
  const std::size_t np = g.np, nc = np / g.points_per_cell, nv = g.cell_data ? nc : np;
  Arrays out;
  std::vector<Array>&points = out.points, &cells = out.cells, &data = out.data;
  points.push_back({"Float64", "", 3, 24ull * np, [&g, np](const Put& put) {
                      for (std::size_t i = 0; i < np; ++i) {
                        double v[3] = {0, 0, 0};
                        g.point(i, v[0], v[1]);
                        put(v, sizeof v);
                      }
                    }});
  cells.push_back({"Int64", "connectivity", 1, 8ull * np, [np](const Put& put) {
                     for (std::size_t i = 0; i < np; ++i) put_value<std::int64_t>(put, static_cast<std::int64_t>(i));
                   }});
  cells.push_back({"Int64", "offsets", 1, 8ull * nc, [&g, nc](const Put& put) {
                     for (std::size_t c = 0; c < nc; ++c)
                       put_value<std::int64_t>(put, static_cast<std::int64_t>((c + 1) * g.points_per_cell));
                   }});
  cells.push_back({"UInt8", "types", 1, nc, [&g, nc](const Put& put) {
                     for (std::size_t c = 0; c < nc; ++c) put_value<std::uint8_t>(put, static_cast<std::uint8_t>(g.vtk_type));
                   }});
  for (const VtuColumn& c : g.scalars)
    data.push_back({"Float64", c.name, 1, 8ull * nv, [&c, nv](const Put& put) {
                      for (std::size_t i = 0; i < nv; ++i) put_value<double>(put, c.at(i));
                    }});
  for (const VtuVector& c : g.vectors)
    data.push_back({"Float64", c.name, 3, 24ull * nv, [&c, nv](const Put& put) {
                      for (std::size_t i = 0; i < nv; ++i) {
                        double v[3] = {0, 0, 0};
                        c.at(i, v[0], v[1]);
                        put(v, sizeof v);
                      }
                    }});
  for (const VtuIntColumn& c : g.ints)
    data.push_back({"Int32", c.name, 1, 4ull * nv, [&c, nv](const Put& put) {
                      for (std::size_t i = 0; i < nv; ++i) put_value<std::int32_t>(put, static_cast<std::int32_t>(c.at(i)));
                    }});
  return out;
}

// The appended data: each array's size (its blocks' compressed sizes, `sizes`, with zlib) and bytes.
void write_appended(std::ostream& o, const Arrays& arrays, const std::vector<std::vector<std::uint64_t>>& sizes, bool z) {
  std::size_t n_array = 0;
  const auto raw = [&](const void* p, std::size_t n) { o.write(static_cast<const char*>(p), static_cast<std::streamsize>(n)); };
  for (auto* group : {&arrays.points, &arrays.cells, &arrays.data})
    for (const Array& a : *group) {
      if (!z) {
        put_value<std::uint64_t>(raw, a.bytes);
        a.emit(raw);
        continue;
      }
      const std::vector<std::uint64_t>& s = sizes[n_array++];
      const std::uint64_t last = a.bytes % kBlock;
      // VTK's compressed header: blocks, block size, size of a partial last block (0: none), then
      // each block's compressed size.
      put_value<std::uint64_t>(raw, s.size());
      put_value<std::uint64_t>(raw, kBlock);
      put_value<std::uint64_t>(raw, last);
      for (std::uint64_t n : s) put_value<std::uint64_t>(raw, n);
      std::size_t block = 0;
      Blocks b(true, [&](const char* p, std::size_t n) {
        if (block >= s.size() || s[block++] != n) throw std::runtime_error("a VTU block compressed to another size");
        raw(p, n);
      });
      a.emit([&](const void* p, std::size_t n) { b.put(p, n); });
      b.finish();
    }
}

void binary(std::ostream& o, const VtuGrid& g) {
  const bool z = vtu_compressed();
  const std::size_t np = g.np, nc = np / g.points_per_cell;
  const Arrays arrays = grid_arrays(g);
  const std::vector<Array>&points = arrays.points, &cells = arrays.cells, &data = arrays.data;

  // The header gives every array's offset in the appended data, so compressed sizes are measured
  // by a first pass (block sizes only are kept), then the blocks are compressed again and written.
  std::vector<std::vector<std::uint64_t>> sizes;
  std::vector<std::uint64_t> offsets;
  std::uint64_t at = 0;
  for (auto* group : {&points, &cells, &data})
    for (const Array& a : *group) {
      offsets.push_back(at);
      if (!z) {
        at += 8 + a.bytes;
        continue;
      }
      std::vector<std::uint64_t> s;
      Blocks b(true, [&](const char*, std::size_t n) { s.push_back(n); });
      a.emit([&](const void* p, std::size_t n) { b.put(p, n); });
      b.finish();
      std::uint64_t total = 0;
      for (std::uint64_t n : s) total += n;
      at += 8 * (3 + s.size()) + total;
      sizes.push_back(std::move(s));
    }

  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\""
    << " header_type=\"UInt64\"" << (z ? " compressor=\"vtkZLibDataCompressor\"" : "") << ">\n"
    << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << np << "\" NumberOfCells=\"" << nc << "\">\n";
  std::size_t k = 0;
  const auto element = [&](const Array& a) {
    o << "<DataArray type=\"" << a.type << "\"";
    if (!a.name.empty()) o << " Name=\"" << a.name << "\"";
    if (a.components != 1) o << " NumberOfComponents=\"" << a.components << "\"";
    o << " format=\"appended\" offset=\"" << offsets[k++] << "\"/>\n";
  };
  o << "<Points>\n";
  element(points[0]);
  o << "</Points>\n<Cells>\n";
  for (const Array& a : cells) element(a);
  o << "</Cells>\n" << (g.cell_data ? "<CellData>\n" : "<PointData>\n");
  for (const Array& a : data) element(a);
  o << (g.cell_data ? "</CellData>\n" : "</PointData>\n")
    << "</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
  write_appended(o, arrays, sizes, z);
  o << "\n</AppendedData>\n</VTKFile>\n";
}

}  // namespace

bool vtu_compressed() {
#ifdef DEM_HAVE_ZLIB
  return true;
#else
  return false;
#endif
}

void write_vtu(std::ostream& o, const VtuGrid& g, bool binary_file) {
  if (binary_file) binary(o, g);
  else ascii(o, g);
}

void write_walls_vtu(const std::string& path, const Geometry& geo, bool binary_file) {
  std::vector<int> active;
  for (std::size_t k = 0; k < geo.walls.size(); ++k)
    if (geo.walls[k].active) active.push_back(static_cast<int>(k));
  VtuGrid g;
  g.np = 2 * active.size();
  g.point = [&](std::size_t i, double& x, double& y) {
    const Wall& w = geo.walls[active[i / 2]];
    x = i % 2 ? w.bx : w.ax;
    y = i % 2 ? w.by : w.ay;
  };
  g.points_per_cell = 2;
  g.vtk_type = 3;  // VTK_LINE
  g.ints = {{"wall", [&](std::size_t c) { return static_cast<long long>(active[c]); }}};
  g.cell_data = true;
  write_stream_atomic(path, [&](std::ostream& out) { write_vtu(out, g, binary_file); });
}

}  // namespace dem
