# cmake --install: the five libraries with their headers, the wbm command, and a CMake package so
# that find_package(wbm) gives wbm::wavelets, wbm::spectral, wbm::fem, wbm::contact, wbm::solvers.
# The scene module (wbm_scene) is linked into the wbm command and not installed as a library.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(wbm_installed_targets)
foreach(module wavelets spectral fem contact solvers)
  set_target_properties(wbm_${module} PROPERTIES EXPORT_NAME ${module})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  list(APPEND wbm_installed_targets wbm_${module})
endforeach()
install(TARGETS ${wbm_installed_targets} EXPORT wbmTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS wbm RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The pictures of `wbm run` / `wbm plot`: found by the command at <bindir>/../share/wbm.
install(PROGRAMS ${PROJECT_SOURCE_DIR}/cli/wbm_plot.py DESTINATION ${CMAKE_INSTALL_DATADIR}/wbm)

set(wbm_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/wbm)
install(EXPORT wbmTargets NAMESPACE wbm:: DESTINATION ${wbm_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/wbmConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/wbmConfig.cmake INSTALL_DESTINATION ${wbm_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/wbmConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/wbmConfig.cmake ${PROJECT_BINARY_DIR}/wbmConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindKLU.cmake ${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindSiconosNumerics.cmake
        DESTINATION ${wbm_cmake_dir})
