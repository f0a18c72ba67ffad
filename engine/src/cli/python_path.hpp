// The PYTHONPATH of the comparison layer's processes (`dem compare`, `dem run --engine`, `dem run
// --pictures`): the source tree first, then the caller's own.
#pragma once

#include <cstdlib>
#include <string>

namespace dem {

inline std::string comparison_python_path() {
  const char* old = std::getenv("PYTHONPATH");
  return std::string(DEM_SOURCE_DIR) + (old && *old ? std::string(":") + old : "");
}

}  // namespace dem
