// The PYTHONPATH of the comparison layer's processes (`dem compare`, `dem run --engine`, `dem run
// --pictures`): the folder that holds the package dem (dem.compare) first, then the caller's own.
// An installed dem (`cmake --install`) finds its own package (PREFIX/DEM_PYTHON_INSTALL_DIR/dem),
// so it runs with the source tree gone; build/dem itself finds its build tree's (build/python/dem,
// linked to the checkout's compare/). Any other dem, a copy of build/dem elsewhere, has none and
// says so, rather than run whatever checkout it was built from.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>

namespace dem {

// The folder holding dem/compare/__init__.py for this binary, or "" with `error` saying why.
inline std::string python_package_root(std::string& error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    error = "cannot read /proc/self/exe to find dem's Python package: " + ec.message();
    return "";
  }
  const auto has_package = [](const fs::path& root) {
    std::error_code e;
    return fs::exists(root / "dem" / "compare" / "__init__.py", e);
  };
  const fs::path installed = self.parent_path().parent_path() / DEM_PYTHON_INSTALL_DIR;
  if (has_package(installed)) return installed.string();
  if (fs::equivalent(self, DEM_BUILD_BINARY, ec) && has_package(DEM_PYTHON_BUILD_DIR)) return DEM_PYTHON_BUILD_DIR;
  error = "dem's Python package (dem.compare) is not found for " + self.string() + ": an installed dem has it in " +
          installed.string() + "/dem (cmake --install), build/dem in " + DEM_PYTHON_BUILD_DIR +
          "/dem; a copy of build/dem elsewhere has none";
  return "";
}

// PYTHONPATH for the comparison layer's processes: the package's folder, then the caller's own;
// "" with `error` when there is no package.
inline std::string comparison_python_path(std::string& error) {
  const std::string root = python_package_root(error);
  if (root.empty()) return "";
  const char* old = std::getenv("PYTHONPATH");
  return root + (old && *old ? std::string(":") + old : "");
}

}  // namespace dem
