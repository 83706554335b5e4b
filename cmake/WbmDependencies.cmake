# All third-party look-ups in one place. Each failure names the Debian package to install;
# scripts/install-deps installs them all.
macro(wbm_require found package)
  if(NOT ${found})
    message(FATAL_ERROR "${ARGN} not found: install ${package} (or run scripts/install-deps as root)")
  endif()
endmacro()

find_package(Eigen3 3.4 QUIET NO_MODULE)
wbm_require(Eigen3_FOUND libeigen3-dev "Eigen 3.4")

find_package(PkgConfig QUIET)
wbm_require(PKG_CONFIG_FOUND pkg-config "pkg-config")
pkg_check_modules(FFTW3 QUIET IMPORTED_TARGET fftw3)
wbm_require(FFTW3_FOUND libfftw3-dev "FFTW 3")

find_package(GSL QUIET)
wbm_require(GSL_FOUND libgsl-dev "GSL")

find_package(Threads REQUIRED)  # the toolchain's threads (oneTBB's, and the python module's)
# oneTBB: the stability of a response curve's points (solvers/), the robustness grid's independent
# continuations (reproduce/ll11_robustness.cpp).
find_package(TBB QUIET CONFIG)
wbm_require(TBB_FOUND libtbb-dev "oneTBB")

list(APPEND CMAKE_MODULE_PATH ${CMAKE_CURRENT_LIST_DIR})
find_package(spectra 1.0 QUIET CONFIG)  # Craig–Bampton's sparse eigenproblem (fem/)
wbm_require(spectra_FOUND libspectra-dev "Spectra")
find_package(KLU QUIET)  # cmake/FindKLU.cmake
# LAPACK: band LU (dgbtrf) of the weighted-residual operator's harmonic blocks
# (kronecker_components.cpp) and tridiagonal LU (dgttrf) of the undamped modes' inverse
# iteration (undamped_modes.cpp), both in solvers/. Debian's reference LAPACK unless the machine chose OpenBLAS before
# (scripts/install-deps).
find_package(LAPACK QUIET)
wbm_require(LAPACK_FOUND liblapack-dev "LAPACK")
find_package(CHOLMOD QUIET)  # cmake/FindCHOLMOD.cmake (Craig–Bampton)
wbm_require(CHOLMOD_FOUND libsuitesparse-dev "SuiteSparse CHOLMOD")
wbm_require(KLU_FOUND libsuitesparse-dev "SuiteSparse KLU")
# Siconos Numerics: the fc2d friction-contact solvers of the Moreau–Jean reference with Coulomb
# friction (solvers/src/reference/friction_contact_step.cpp).
find_package(SiconosNumerics QUIET)  # cmake/FindSiconosNumerics.cmake
wbm_require(SiconosNumerics_FOUND libsiconos-numerics-dev "Siconos Numerics")

# Scenes and the `wbm` command.
find_package(tomlplusplus QUIET)
wbm_require(tomlplusplus_FOUND libtomlplusplus-dev "toml++")
find_package(nlohmann_json 3.10 QUIET)
wbm_require(nlohmann_json_FOUND nlohmann-json3-dev "nlohmann-json")
find_package(CLI11 2.1 QUIET)
wbm_require(CLI11_FOUND libcli11-dev "CLI11")
pkg_check_modules(MATIO QUIET IMPORTED_TARGET matio)  # [output] formats = ["mat"]
wbm_require(MATIO_FOUND libmatio-dev "matio")
# Python: Debian's interpreter, where scripts/install-deps puts matplotlib, numpy and pytest (the
# first python3 on PATH may be another one, e.g. a pyenv shim without them), unless
# -DPython3_EXECUTABLE=… chooses another. Set before any find_package(Python3).
if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter (module wbm, its tests, plots)")
endif()
if(WBM_BUILD_REPRODUCE)
  # An interpreter that imports matplotlib: the first python3 on PATH may not be Debian's.
  set(WBM_PYTHON "" CACHE FILEPATH "Python interpreter with matplotlib, for reproduce/plot.py")
  if(NOT WBM_PYTHON)
    find_package(Python3 QUIET COMPONENTS Interpreter)
    foreach(candidate ${Python3_EXECUTABLE} /usr/bin/python3)
      execute_process(COMMAND ${candidate} -c "import matplotlib"
                      RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
      if(rc EQUAL 0)
        set(WBM_PYTHON ${candidate} CACHE FILEPATH "" FORCE)
        break()
      endif()
    endforeach()
  endif()
  wbm_require(WBM_PYTHON python3-matplotlib "A python3 that imports matplotlib")
endif()

if(WBM_BUILD_PYTHON)
  find_package(Python3 QUIET COMPONENTS Interpreter Development.Module)
  wbm_require(Python3_Development.Module_FOUND python3-dev "Python 3 headers")
  set(PYBIND11_FINDPYTHON ON)
  find_package(pybind11 2.6 QUIET CONFIG)
  wbm_require(pybind11_FOUND pybind11-dev "pybind11")
endif()

if(WBM_BUILD_TESTS)
  find_package(GTest QUIET)
  wbm_require(GTest_FOUND libgtest-dev "GoogleTest")
endif()
if(WBM_BUILD_BENCH)
  find_package(benchmark QUIET)
  wbm_require(benchmark_FOUND libbenchmark-dev "Google Benchmark")
endif()
