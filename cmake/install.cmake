# `cmake --install build [--prefix P]`: the engine (P/bin/dem); the Python package dem
# (P/<DEM_PYTHON_INSTALL_DIR>/dem: __init__.py, the engine module _engine when built, compare as a
# link to P/share/dem/compare); the scenes (P/share/dem/reference_inputs) and the comparison layer
# beside them (P/share/dem/compare), where its code finds the scenes. The installed dem's Python
# processes (`dem compare`, `--pictures`, `--engine`) import that package (cli/python_path.hpp):
# they run with the source tree gone.
include(GNUInstallDirs)
install(TARGETS dem RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES engine/python/dem/__init__.py DESTINATION ${DEM_PYTHON_INSTALL_DIR}/dem)
if(DEM_PYTHON_MODULE)
  install(TARGETS dem_python LIBRARY DESTINATION ${DEM_PYTHON_INSTALL_DIR}/dem)
endif()
install(DIRECTORY reference_inputs DESTINATION ${CMAKE_INSTALL_DATADIR}/dem)
install(DIRECTORY compare DESTINATION ${CMAKE_INSTALL_DATADIR}/dem PATTERN "__pycache__" EXCLUDE)
install(CODE "
  set(dir \"${DEM_PYTHON_INSTALL_DIR}\")
  if(NOT IS_ABSOLUTE \"\${dir}\")
    set(dir \"\${CMAKE_INSTALL_PREFIX}/\${dir}\")
  endif()
  set(layer \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DATADIR}/dem/compare\")
  file(RELATIVE_PATH target \"\${dir}/dem\" \"\${layer}\")
  message(STATUS \"Installing: \$ENV{DESTDIR}\${dir}/dem/compare -> \${target}\")
  file(CREATE_LINK \"\${target}\" \"\$ENV{DESTDIR}\${dir}/dem/compare\" SYMBOLIC)
")
