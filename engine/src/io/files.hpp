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
// A JSON number, or null when not finite.
nlohmann::ordered_json finite_or_null(double v);

}  // namespace dem
