# FindTetGen
# ----------
# Finds TetGen as packaged by Debian (libtet1.5-dev), which ships a header and a
# shared library but no CMake configuration.
#
# Imported target:
#   TetGen::TetGen   include directory, library, and the TETLIBRARY definition
#                    that tetgen.h needs to expose its library interface.
# Result variables:
#   TetGen_FOUND, TetGen_INCLUDE_DIR, TetGen_LIBRARY

find_path(TetGen_INCLUDE_DIR NAMES tetgen.h)
find_library(TetGen_LIBRARY NAMES tet tetgen)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(TetGen REQUIRED_VARS TetGen_LIBRARY TetGen_INCLUDE_DIR)

if(TetGen_FOUND AND NOT TARGET TetGen::TetGen)
  add_library(TetGen::TetGen UNKNOWN IMPORTED)
  set_target_properties(TetGen::TetGen PROPERTIES
    IMPORTED_LOCATION "${TetGen_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TetGen_INCLUDE_DIR}"
    INTERFACE_COMPILE_DEFINITIONS "TETLIBRARY")
endif()
mark_as_advanced(TetGen_INCLUDE_DIR TetGen_LIBRARY)
