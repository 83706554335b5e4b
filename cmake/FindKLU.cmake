# FindKLU: SuiteSparse's KLU sparse LU (Debian libsuitesparse-dev; its 5.x packages ship neither
# CMake nor pkg-config files). Sets KLU_FOUND and defines the imported target KLU::KLU: the
# include directory of klu.h and the libraries klu, amd, colamd, btf, suitesparseconfig, in link
# order. Used by wbm::solvers (SparseLu) and by find_package(wbm) for the static link.
find_path(KLU_INCLUDE_DIR klu.h PATH_SUFFIXES suitesparse)
set(_klu_libraries)
foreach(_klu_lib klu amd colamd btf suitesparseconfig)
  find_library(KLU_${_klu_lib}_LIBRARY ${_klu_lib})
  list(APPEND _klu_libraries KLU_${_klu_lib}_LIBRARY)
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(KLU REQUIRED_VARS KLU_INCLUDE_DIR ${_klu_libraries})
if(KLU_FOUND AND NOT TARGET KLU::KLU)
  add_library(KLU::KLU INTERFACE IMPORTED)
  set(_klu_link)
  foreach(_klu_var ${_klu_libraries})
    list(APPEND _klu_link ${${_klu_var}})
  endforeach()
  set_target_properties(KLU::KLU PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${KLU_INCLUDE_DIR}"
                                            INTERFACE_LINK_LIBRARIES "${_klu_link}")
endif()
mark_as_advanced(KLU_INCLUDE_DIR ${_klu_libraries})
