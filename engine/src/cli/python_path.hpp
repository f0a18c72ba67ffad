// The PYTHONPATH of the comparison layer's processes (`dem compare`, `dem run --engine`, `dem run
// --pictures`): the folder that holds compare/ first, then the caller's own. An installed dem
// (`cmake --install`) finds its own copy in PREFIX/share/dem, beside the scenes it reads, so it
// runs with the source tree gone; a dem in a build tree finds the checkout it was built from.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace dem {

// PREFIX/share/dem when this binary is PREFIX/bin/dem and compare/ was installed there, else "".
inline std::string installed_python_root() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const std::filesystem::path root = self.parent_path().parent_path() / "share" / "dem";
  return std::filesystem::exists(root / "compare" / "__init__.py", ec) ? root.string() : "";
}

inline std::string comparison_python_path() {
  const char* old = std::getenv("PYTHONPATH");
  const std::string installed = installed_python_root();
  const std::string root = installed.empty() ? std::string(DEM_SOURCE_DIR) : installed;
  return root + (old && *old ? std::string(":") + old : "");
}

}  // namespace dem
