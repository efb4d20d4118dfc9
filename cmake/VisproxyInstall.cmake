# The installed package: `cmake --install BUILD --prefix P` puts
#   P/lib/libvisproxy.so         every library module in one shared library
#   P/include/visproxy/...        the modules' headers (#include <visproxy/render/renderer.h>)
#   P/bin/visproxy                the command-line tool
#   P/share/visproxy/schemas      the JSON schemas of every file visproxy reads or writes
#   P/lib/cmake/visproxy          visproxyConfig.cmake, its version file and the targets
#   P/lib/pkgconfig/visproxy.pc   for pkg-config
#   P/lib/python3/dist-packages   the Python module (import visproxy), where Debian's python3 looks
# Headers name nothing from CGAL, Embree, TBB, OpenMesh, TetGen or Assimp: those stay inside the
# shared library (tests/package checks the installed tree).

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(VISPROXY_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/visproxy")
set(VISPROXY_INSTALL_SCHEMADIR "${CMAKE_INSTALL_DATADIR}/visproxy/schemas")

install(TARGETS visproxy_shared EXPORT visproxyTargets
        LIBRARY DESTINATION "${CMAKE_INSTALL_LIBDIR}"
        INCLUDES DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
install(TARGETS visproxy RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
# visproxy batch over a Dask cluster, as `visproxy-dask` (needs python3-distributed).
install(PROGRAMS "${PROJECT_SOURCE_DIR}/apps/dask/visproxy_dask.py" DESTINATION "${CMAKE_INSTALL_BINDIR}" RENAME visproxy-dask)
# The module finds libvisproxy.so three levels up, in the prefix's library folder.
set_target_properties(visproxy_python PROPERTIES INSTALL_RPATH "$ORIGIN/../../../${CMAKE_INSTALL_LIBDIR}")
install(TARGETS visproxy_python LIBRARY DESTINATION "lib/python3/dist-packages")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/lib/visproxy/" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/visproxy"
        FILES_MATCHING PATTERN "*.h"
        PATTERN "detail" EXCLUDE
        PATTERN "embree_support.h" EXCLUDE
        PATTERN "assimp_support.h" EXCLUDE
        PATTERN "alpha_wrap_shared.h" EXCLUDE)
install(DIRECTORY "${PROJECT_SOURCE_DIR}/data/schemas/" DESTINATION "${VISPROXY_INSTALL_SCHEMADIR}")
install(EXPORT visproxyTargets NAMESPACE visproxy:: DESTINATION "${VISPROXY_INSTALL_CMAKEDIR}")

configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/visproxyConfig.cmake.in"
                              "${PROJECT_BINARY_DIR}/visproxyConfig.cmake"
                              INSTALL_DESTINATION "${VISPROXY_INSTALL_CMAKEDIR}"
                              PATH_VARS VISPROXY_INSTALL_SCHEMADIR)
# 0.x: a minor version may change the API, so only the same major.minor is compatible.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/visproxyConfigVersion.cmake"
                                 COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/visproxyConfig.cmake" "${PROJECT_BINARY_DIR}/visproxyConfigVersion.cmake"
        DESTINATION "${VISPROXY_INSTALL_CMAKEDIR}")
configure_file("${PROJECT_SOURCE_DIR}/cmake/visproxy.pc.in" "${PROJECT_BINARY_DIR}/visproxy.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/visproxy.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
