# FindARPACK: arpack-ng, the implicitly restarted Lanczos/Arnoldi library, with its ISO-C
# bindings (<arpack/arpack.h>: dsaupd_c, dseupd_c).
#
# Uses ARPACK's pkg-config file (arpack.pc) as a hint when pkg-config is available, else searches
# the usual places. Defines
#
#   ARPACK::ARPACK        imported target (library and include directory)
#   ARPACK_FOUND, ARPACK_INCLUDE_DIR, ARPACK_LIBRARY
#
# Set ARPACK_ROOT to search a non-system installation first.
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(PC_ARPACK QUIET arpack)
endif()
find_path(ARPACK_INCLUDE_DIR arpack/arpack.h HINTS ${PC_ARPACK_INCLUDEDIR})
find_library(ARPACK_LIBRARY NAMES arpack HINTS ${PC_ARPACK_LIBRARY_DIRS})

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(ARPACK REQUIRED_VARS ARPACK_LIBRARY ARPACK_INCLUDE_DIR)
mark_as_advanced(ARPACK_INCLUDE_DIR ARPACK_LIBRARY)

if(ARPACK_FOUND AND NOT TARGET ARPACK::ARPACK)
  add_library(ARPACK::ARPACK UNKNOWN IMPORTED)
  set_target_properties(ARPACK::ARPACK PROPERTIES
    IMPORTED_LOCATION "${ARPACK_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${ARPACK_INCLUDE_DIR}")
endif()
