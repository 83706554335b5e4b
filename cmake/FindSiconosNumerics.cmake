# FindSiconosNumerics: the numerics library of Siconos (Debian libsiconos-numerics-dev): the
# friction-contact solvers (fc2d) of the Moreau–Jean reference with Coulomb friction. Its
# siconos-config.cmake is not used: it checks for the `siconos` script of the full distribution
# (not in this package) and sets CMAKE_CXX_STANDARD to 11 in the caller's scope. Sets
# SiconosNumerics_FOUND and defines the imported target SiconosNumerics::numerics: the include
# directory of SiconosConfig.h (its headers include it by that name; include them as
# <siconos/numerics/…>) and libsiconos_numerics. Used by wbm::solvers and by find_package(wbm) for
# the static link.
find_path(SiconosNumerics_INCLUDE_DIR SiconosConfig.h PATH_SUFFIXES siconos)
find_library(SiconosNumerics_LIBRARY siconos_numerics)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SiconosNumerics REQUIRED_VARS SiconosNumerics_INCLUDE_DIR SiconosNumerics_LIBRARY)
if(SiconosNumerics_FOUND AND NOT TARGET SiconosNumerics::numerics)
  add_library(SiconosNumerics::numerics UNKNOWN IMPORTED)
  set_target_properties(SiconosNumerics::numerics PROPERTIES IMPORTED_LOCATION "${SiconosNumerics_LIBRARY}"
                        INTERFACE_INCLUDE_DIRECTORIES "${SiconosNumerics_INCLUDE_DIR}")
endif()
mark_as_advanced(SiconosNumerics_INCLUDE_DIR SiconosNumerics_LIBRARY)
