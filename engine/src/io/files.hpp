// The ground floor of the outputs: files written whole or not at all, and numbers as text.
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

namespace dem {

// Atomic text file write: PATH.tmp, renamed to PATH when complete (a run killed meanwhile
// leaves the old file or none, never half of one).
void write_file_atomic(const std::string& path, const std::string& text);
// The same, streaming: `write` fills PATH.tmp, renamed to PATH when complete.
void write_stream_atomic(const std::string& path, const std::function<void(std::ostream&)>& write);

// A double at full precision, the bytes of printf's "%.17g": std::to_chars with precision 17 is
// specified as that printf in the "C" locale, and skips the format parsing, the locale and the
// multi-precision digit loop of glibc's printf (a discharge's wall series formats about 100k
// numbers; printf was a fifth of such a run's time). Digits17 holds the text without a heap
// allocation (17 digits, a sign and an exponent pass std::string's inline buffer), for streams.
struct Digits17 {
  char text[32];
  std::size_t size;
};
Digits17 digits17(double v);
inline std::ostream& operator<<(std::ostream& o, const Digits17& d) {
  return o.write(d.text, static_cast<std::streamsize>(d.size));
}
std::string fmt17(double v);
// A time as the user would write it: t moved onto the step grid, n dt rounded to 15 significant
// digits (an accumulated t reads 0.0099999999999999672 where 200 steps of 5e-5 s are 0.01); a t
// off the grid (a state file saved with another dt) is returned as it is.
double on_step_grid(double t, double dt);
// The shortest text that reads back as t (0.571, not %.17g's 0.57099999999999995).
std::string time_text(double t);
// A JSON number, or null when not finite.
nlohmann::ordered_json finite_or_null(double v);

}  // namespace dem
