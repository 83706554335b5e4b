# ctest install.examples: installs this build into a fresh prefix, builds examples/ against it
# with find_package(wbm) as an outside project would, runs the examples and the installed wbm.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -P TestInstall.cmake
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "TestInstall.cmake: -D${var}=... is required")
  endif()
endforeach()

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

function(expect text pattern)
  if(NOT text MATCHES "${pattern}")
    message(FATAL_ERROR "expected output matching \"${pattern}\", got:\n${text}")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(module wavelets spectral fem contact solvers)
  file(GLOB header ${prefix}/include/wbm/${module}/*.hpp)
  if(NOT header)
    message(FATAL_ERROR "no installed headers for wbm::${module}")
  endif()
endforeach()
# The Python module lands under the prefix (never in the system's site-packages) and imports.
if(PYTHON)
  file(GLOB_RECURSE python_module ${prefix}/lib/python*/site-packages/wbm*.so)
  if(NOT python_module)
    message(FATAL_ERROR "cmake --install did not put the Python module wbm under ${prefix}/lib/python*/site-packages")
  endif()
  get_filename_component(site ${python_module} DIRECTORY)
  step("import the installed wbm" ${CMAKE_COMMAND} -E env PYTHONPATH=${site} ${PYTHON} -c
       "print(round(__import__('wbm').natural_frequencies_hz(__import__('wbm').rod(210e9, 7800.0, 1e-4, 1.0, 20))[0], 1))")
  expect("${step_output}" "^1297\\.5")
endif()
step("configure examples" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples -B ${WORK_DIR}/build
     -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
step("build examples" ${CMAKE_COMMAND} --build ${WORK_DIR}/build -j 2)

# DB6 Γ^{0,2} at J = 3: diagonal 2^{2J} · (−295/56) = −337.142857143 [LRT91].
step("db6_connection_coefficients" ${WORK_DIR}/build/db6_connection_coefficients)
expect("${step_output}" "DB6, J = 3, M = 8")
expect("${step_output}" "^[^\n]*\n +-337\\.142857143")
# Case 1 of [JL14 Table 1] with the installed solvers.
step("solve_case1" ${WORK_DIR}/build/solve_case1)
expect("${step_output}" "Fourier:Fourier M = 64: converged")
step("installed wbm --version" ${prefix}/bin/wbm --version)
expect("${step_output}" "^wbm 0\\.1\\.0")
# The installed command runs a scene and draws it with the installed share/wbm/wbm_plot.py.
if(NOT EXISTS ${prefix}/share/wbm/wbm_plot.py)
  message(FATAL_ERROR "cmake --install did not put wbm_plot.py in ${prefix}/share/wbm")
endif()
step("installed wbm run" ${prefix}/bin/wbm run ${SOURCE_DIR}/examples/scenes/massless_contact_node.toml -o ${WORK_DIR}/run)
expect("${step_output}" "drew 1 picture\\(s\\)")
if(NOT EXISTS ${WORK_DIR}/run/time_histories.png)
  message(FATAL_ERROR "the installed wbm run drew no time_histories.png")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
message(STATUS "install.examples: find_package(wbm) consumers built and ran")
