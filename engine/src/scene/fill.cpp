#include "scene/fill.hpp"

#include <cmath>
#include <sstream>

namespace dem {

std::string lattice_geometry(const LatticeSpec& L, double width, LatticeGeometry& out) {
  std::ostringstream why;
  if (L.s < 2) return "s must be at least 2";
  const double d = 2 * L.radius + L.gap;
  out.pitch = (width - 2 * L.radius - 2 * L.gap) / (L.s - 1);
  if (out.pitch < d) {
    why << "s = " << L.s << " discs of radius " << L.radius << " do not fit in width " << width
        << " without side contacts (pitch " << out.pitch << " < 2r + gap = " << d << ")";
    return why.str();
  }
  if (out.pitch / 2 >= d) {
    why << "s = " << L.s << " is too few for width " << width << ": rows cannot touch (pitch/2 = "
        << out.pitch / 2 << " >= 2r + gap)";
    return why.str();
  }
  out.row_height = std::sqrt(d * d - 0.25 * out.pitch * out.pitch);
  const long pair = 2L * L.s - 1;
  auto count = [&](long rows) { return (rows + 1) / 2 * L.s + rows / 2 * (L.s - 1); };
  if (L.rows > 0) {
    out.rows = L.rows;
  } else {
    out.rows = std::max(1L, 2 * L.count / pair);
    while (std::labs(count(out.rows + 1) - L.count) < std::labs(count(out.rows) - L.count)) ++out.rows;
    while (out.rows > 1 && std::labs(count(out.rows - 1) - L.count) <= std::labs(count(out.rows) - L.count)) --out.rows;
  }
  out.n = count(out.rows);
  return "";
}

void lattice_centres(const LatticeSpec& L, const LatticeGeometry& g, double x0, double y0,
                     std::vector<double>& x, std::vector<double>& y) {
  x.clear();
  y.clear();
  for (long row = 0; row < g.rows; ++row) {
    const bool full = row % 2 == 0;
    const int n = full ? L.s : L.s - 1;
    const double first = x0 + L.radius + L.gap + (full ? 0.0 : 0.5 * g.pitch);
    const double yc = y0 + L.radius + L.gap + row * g.row_height;
    for (int k = 0; k < n; ++k) {
      x.push_back(first + k * g.pitch);
      y.push_back(yc);
    }
  }
}

}  // namespace dem
