# `cmake --install build --prefix P` (docs/install.md): the CLI, the two shared libraries (capi/), the
# public headers and the CMake package shadowtiles (targets shadowtiles::client, shadowtiles::c) and
# pkg-config files shadowtiles (C) and shadowtiles-client (C++).
include(CMakePackageConfigHelpers)
set(SHADOWTILES_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/shadowtiles)

install(TARGETS shadowtiles RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(TARGETS shadowtiles_client shadowtiles_c EXPORT shadowtilesTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT libraries NAMELINK_COMPONENT development)

# C++ headers keep their layer folders (#include "client/shadow_map.hpp") under include/shadowtiles/;
# the C header sits at include/shadowtiles.h.
foreach(layer common store codec client)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${layer}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/shadowtiles/${layer}
          COMPONENT development FILES_MATCHING PATTERN "*.hpp")
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/capi/shadowtiles.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development)

install(EXPORT shadowtilesTargets NAMESPACE shadowtiles:: DESTINATION ${SHADOWTILES_CMAKE_DIR} COMPONENT development)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/shadowtilesConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/shadowtilesConfig.cmake INSTALL_DESTINATION ${SHADOWTILES_CMAKE_DIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/shadowtilesConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)  # 0.x: the C++ API may change per minor
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/shadowtilesConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/shadowtilesConfigVersion.cmake
        DESTINATION ${SHADOWTILES_CMAKE_DIR} COMPONENT development)

file(RELATIVE_PATH SHADOWTILES_PC_TO_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
foreach(pc shadowtiles shadowtiles-client)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/${pc}.pc.in ${CMAKE_CURRENT_BINARY_DIR}/${pc}.pc @ONLY)
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${pc}.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT development)
endforeach()

# The Python module (ctypes over libshadowtiles.so.1; docs/python.md) under
# PREFIX/lib/python3/dist-packages (Debian's layout; PYTHONPATH for other prefixes). It finds the
# library through _install_paths.py, a path relative to itself, so the prefix may move.
set(SHADOWTILES_PYTHON_DIR lib/python3/dist-packages CACHE STRING "Install folder of the Python module, under the prefix")
file(RELATIVE_PATH SHADOWTILES_PYTHON_TO_LIB /prefix/${SHADOWTILES_PYTHON_DIR}/shadowtiles
     /prefix/${CMAKE_INSTALL_LIBDIR}/libshadowtiles.so.${SHADOWTILES_C_SOVERSION})
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/python/_install_paths.py
     "# Written by cmake --install: the C library relative to this package.\nLIBRARY_RELATIVE = \"${SHADOWTILES_PYTHON_TO_LIB}\"\n")
install(FILES ${PROJECT_SOURCE_DIR}/python/shadowtiles/__init__.py ${CMAKE_CURRENT_BINARY_DIR}/python/_install_paths.py
        DESTINATION ${SHADOWTILES_PYTHON_DIR}/shadowtiles COMPONENT python)
