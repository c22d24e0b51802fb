# `cpack --config build/CPackConfig.cmake` (or `cmake --build build --target package`): a Debian
# package shadowtiles_VERSION_ARCH.deb with the CLI and server, the libraries, headers, Python module
# and the systemd unit shadowtiles-serve@.service (packaging/, docs/install.md). Linux only.
if(NOT CMAKE_SYSTEM_NAME STREQUAL "Linux")
  return()
endif()
install(FILES ${PROJECT_SOURCE_DIR}/packaging/shadowtiles-serve@.service DESTINATION lib/systemd/system COMPONENT service)
install(FILES ${PROJECT_SOURCE_DIR}/config/serve.json ${PROJECT_SOURCE_DIR}/config/README.md
        DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples COMPONENT service)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME shadowtiles)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "shadowtiles maintainers <shadowtiles@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "lossless compressed shadow maps of huge static worlds (Linux only)")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "Builds, serves and queries lossless compressed shadow maps (MH, MMH, DAG-MH).\nLinux only. Ships the shadowtiles CLI and HTTP server (systemd unit\nshadowtiles-serve@NAME reading /etc/shadowtiles/NAME.json), the client\nlibraries libshadowtiles.so.1 (stable C API) and libshadowtiles_client\n(C++), headers, CMake and pkg-config files and the Python module.")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # shadowtiles_0.1.0_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)   # Depends from the binaries' libraries (dpkg-shlibdeps)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)  # shlibs file and the ldconfig trigger for libshadowtiles.so.1
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-numpy")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${PROJECT_SOURCE_DIR}/packaging/postinst ${PROJECT_SOURCE_DIR}/packaging/postrm
    ${PROJECT_SOURCE_DIR}/packaging/triggers)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)
include(CPack)
