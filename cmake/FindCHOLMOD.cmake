# FindCHOLMOD: SuiteSparse's CHOLMOD supernodal sparse Cholesky (Debian libsuitesparse-dev; its
# 5.x packages ship neither CMake nor pkg-config files). Sets CHOLMOD_FOUND and defines the
# imported target CHOLMOD::CHOLMOD: the include directory of cholmod.h and the libraries cholmod,
# suitesparseconfig. Used by wbm::fem (Craig–Bampton) and by find_package(wbm) for the static link.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_cholmod_LIBRARY cholmod)
find_library(CHOLMOD_suitesparseconfig_LIBRARY suitesparseconfig)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD REQUIRED_VARS CHOLMOD_INCLUDE_DIR CHOLMOD_cholmod_LIBRARY
                                  CHOLMOD_suitesparseconfig_LIBRARY)
if(CHOLMOD_FOUND AND NOT TARGET CHOLMOD::CHOLMOD)
  add_library(CHOLMOD::CHOLMOD INTERFACE IMPORTED)
  set_target_properties(CHOLMOD::CHOLMOD PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
                        INTERFACE_LINK_LIBRARIES "${CHOLMOD_cholmod_LIBRARY};${CHOLMOD_suitesparseconfig_LIBRARY}")
endif()
mark_as_advanced(CHOLMOD_INCLUDE_DIR CHOLMOD_cholmod_LIBRARY CHOLMOD_suitesparseconfig_LIBRARY)
