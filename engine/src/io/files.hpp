// The ground floor of the outputs: files written whole or not at all, and numbers as text.
#pragma once

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

// A double at full precision (%.17g), and a JSON number or null when not finite.
std::string fmt17(double v);
nlohmann::ordered_json finite_or_null(double v);

}  // namespace dem
