# The Python package dem in this build tree, build/python/dem: its __init__.py and compare/ as
# links to the checkout's (an edit needs no rebuild), and the engine's module _engine when it is
# built (engine/python). Laid out with or without the module: dem.compare needs no engine module.
set(DEM_PYTHON_BUILD_DIR ${CMAKE_BINARY_DIR}/python)
file(MAKE_DIRECTORY ${DEM_PYTHON_BUILD_DIR}/dem)
file(CREATE_LINK ${PROJECT_SOURCE_DIR}/engine/python/dem/__init__.py ${DEM_PYTHON_BUILD_DIR}/dem/__init__.py SYMBOLIC)
file(CREATE_LINK ${PROJECT_SOURCE_DIR}/compare ${DEM_PYTHON_BUILD_DIR}/dem/compare SYMBOLIC)

# Where `cmake --install` puts the package, below the prefix: Debian's python looks in
# PREFIX/lib/python3.X/dist-packages for PREFIX /usr/local. The installed dem finds its package
# there (engine/src/cli/python_path.hpp).
execute_process(COMMAND ${DEM_PYTHON} -c "import sys; print('lib/python%d.%d/dist-packages' % sys.version_info[:2])"
                OUTPUT_VARIABLE DEM_PYTHON_SITE_DEFAULT OUTPUT_STRIP_TRAILING_WHITESPACE)
set(DEM_PYTHON_INSTALL_DIR ${DEM_PYTHON_SITE_DEFAULT} CACHE STRING "Where the Python package dem installs, below the prefix")

# build/dem.pth: this build's package on the path; scripts/build.sh copies it into the site
# folder so that `import dem` (and dem.compare) works from any folder.
file(WRITE ${CMAKE_BINARY_DIR}/dem.pth "${DEM_PYTHON_BUILD_DIR}\n")
