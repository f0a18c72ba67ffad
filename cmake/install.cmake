# `cmake --install build [--prefix P]`: the engine (P/bin/dem), the Python module (P/lib/pythonX.Y/
# dist-packages/dem.*.so, where Debian's python looks under /usr/local), the scenes
# (P/share/dem/reference_inputs) and the comparison layer beside them (P/share/dem/compare), where
# the installed dem finds it (cli/python_path.hpp): `dem compare`, `--pictures` and `--engine`
# work with the source tree gone, and compare/ is on no Python's path but dem's own processes'.
include(GNUInstallDirs)
install(TARGETS dem RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(DEM_PYTHON_MODULE)
  execute_process(COMMAND ${DEM_PYTHON} -c "import sys; print('lib/python%d.%d/dist-packages' % sys.version_info[:2])"
                  OUTPUT_VARIABLE DEM_PYTHON_SITE_DEFAULT OUTPUT_STRIP_TRAILING_WHITESPACE)
  set(DEM_PYTHON_INSTALL_DIR ${DEM_PYTHON_SITE_DEFAULT} CACHE STRING "Where the module dem installs, below the prefix")
  install(TARGETS dem_python LIBRARY DESTINATION ${DEM_PYTHON_INSTALL_DIR})
endif()
install(DIRECTORY reference_inputs DESTINATION ${CMAKE_INSTALL_DATADIR}/dem)
install(DIRECTORY compare DESTINATION ${CMAKE_INSTALL_DATADIR}/dem PATTERN "__pycache__" EXCLUDE)
