# The installed package as a plugin author uses it (plugins/example/README.md):
# install hamal into a prefix inside the build tree, build plugins/example on
# its own against it with find_package(hamal), run the plugin's own test (the
# conformance suite, hamal::testing, on its back-end), load the plugin into
# the installed hamal_solve and solve a graph that needs both its factor kind
# and its back-end. Run by ctest (tests/CMakeLists.txt) with
#   -DHAMAL_BINARY_DIR=<build> -DHAMAL_SOURCE_DIR=<source> [-DLAUNCHER=ccache]
cmake_minimum_required(VERSION 3.19)
set(work ${HAMAL_BINARY_DIR}/install_test)
set(prefix ${work}/prefix)
file(REMOVE_RECURSE ${work})
file(MAKE_DIRECTORY ${work})

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

run("cmake --install" ${CMAKE_COMMAND} --install ${HAMAL_BINARY_DIR} --prefix ${prefix})
foreach(installed include/hamal/core/plugin.h include/hamal/protocol/thesis_protocol.h
                  include/hamal/core/backend_kit.h include/hamal/conformance/backend_conformance.h)
  if(NOT EXISTS ${prefix}/${installed})
    message(FATAL_ERROR "not installed: ${installed}")
  endif()
endforeach()
file(GLOB_RECURSE config ${prefix}/*/hamalConfig.cmake)
if(NOT config)
  message(FATAL_ERROR "no hamalConfig.cmake under ${prefix}")
endif()

set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run("configuring plugins/example against the installed package"
    ${CMAKE_COMMAND} -S ${HAMAL_SOURCE_DIR}/plugins/example -B ${work}/plugin
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix} ${launcher})
run("building the plugin" ${CMAKE_COMMAND} --build ${work}/plugin)
set(plugin ${work}/plugin/libhamal_example_plugin.so)
if(NOT EXISTS ${plugin})
  message(FATAL_ERROR "the plugin was not built at ${plugin}")
endif()

# The plugin's own test, as its author runs it: ctest in the plugin's build.
run("the plugin's conformance test" ${CMAKE_CTEST_COMMAND} --test-dir ${work}/plugin
    --output-on-failure)
if(NOT output MATCHES "100% tests passed, 0 tests failed out of 1")
  message(FATAL_ERROR "the plugin's conformance test did not run:\n${output}")
endif()
run("the conformance suite's listing" ${work}/plugin/hamal_example_conformance --gtest_brief=1)
if(NOT output MATCHES "PASSED.*15 tests")
  message(FATAL_ERROR "the conformance suite did not run its 15 tests:\n${output}")
endif()

# Odometry as EDGE_SE2, the loop closure as the plugin's EDGE_SE2_CAUCHY,
# solved by the plugin's back-end.
file(WRITE ${work}/square.g2o
"EDGE_SE2 0 1 1.0 0.0 1.5708 100 0 0 100 0 400
EDGE_SE2 1 2 1.0 0.0 1.5708 100 0 0 100 0 400
EDGE_SE2 2 3 1.0 0.0 1.5708 100 0 0 100 0 400
EDGE_SE2_CAUCHY 3 0 1.0 0.0 1.5708 100 0 0 100 0 400 1.0
")
run("hamal_solve with the plugin" ${prefix}/bin/hamal_solve --plugin ${plugin}
    --backend dense-gauss-newton ${work}/square.g2o)
if(NOT output MATCHES "back-end: +dense-gauss-newton" OR NOT output MATCHES "status: +ok")
  message(FATAL_ERROR "unexpected output of hamal_solve:\n${output}")
endif()
message(STATUS "installed hamal_solve loaded the out-of-tree plugin:\n${output}")
