#include "io/files.hpp"

#include <cmath>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace dem {

void write_stream_atomic(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    write(out);
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

void write_file_atomic(const std::string& path, const std::string& text) {
  write_stream_atomic(path, [&](std::ostream& out) { out << text; });
}

Digits17 digits17(double v) {
  Digits17 d;
  // 32 bytes hold the longest, "-2.2250738585072014e-308" (24), and "-nan".
  const std::to_chars_result r = std::to_chars(d.text, d.text + sizeof d.text, v, std::chars_format::general, 17);
  d.size = static_cast<std::size_t>(r.ptr - d.text);
  return d;
}

std::string fmt17(double v) {
  const Digits17 d = digits17(v);
  return std::string(d.text, d.size);
}

double on_step_grid(double t, double dt) {
  if (!(dt > 0) || !std::isfinite(t)) return t;
  const double n = std::nearbyint(t / dt);
  if (!(std::abs(t - n * dt) <= 1e-2 * dt)) return t;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", n * dt);
  return std::strtod(buf, nullptr);
}

std::string time_text(double t) {
  char buf[32];
  const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, t);
  return std::string(buf, static_cast<std::size_t>(r.ptr - buf));
}

nlohmann::ordered_json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

}  // namespace dem
