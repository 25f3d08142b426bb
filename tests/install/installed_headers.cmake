# The installed include tree stands alone (docs/ARCHITECTURE.md, "Public
# headers"): install hamal into a prefix inside the build tree, then
#  1. every quoted #include of an installed header names an installed header
#     (a public header that includes a back-end's internals would make the
#     internals public, or leave the user a header that cannot compile);
#  2. each installed header compiles alone in a project that knows hamal
#     only through find_package(hamal), so no include path of the build
#     (CHOLMOD's, igraph's, the source tree) hides a missing one.
# Run by ctest (tests/CMakeLists.txt) with
#   -DHAMAL_BINARY_DIR=<build> [-DLAUNCHER=ccache]
cmake_minimum_required(VERSION 3.19)
set(work ${HAMAL_BINARY_DIR}/installed_headers_test)
set(prefix ${work}/prefix)
file(REMOVE_RECURSE ${work})
file(MAKE_DIRECTORY ${work})

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
endfunction()

run("cmake --install" ${CMAKE_COMMAND} --install ${HAMAL_BINARY_DIR} --prefix ${prefix})
set(include_root ${prefix}/include/hamal)
file(GLOB_RECURSE headers RELATIVE ${include_root} ${include_root}/*.h)
list(SORT headers)
list(LENGTH headers count)
if(count EQUAL 0)
  message(FATAL_ERROR "no header installed under ${include_root}")
endif()

# 1. The quoted includes, line by line.
set(missing "")
foreach(header ${headers})
  file(STRINGS ${include_root}/${header} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  foreach(line ${lines})
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" included "${line}")
    if(NOT EXISTS ${include_root}/${included})
      string(APPEND missing "\n  ${header} includes ${included}, which is not installed")
    endif()
  endforeach()
endforeach()
if(missing)
  message(FATAL_ERROR "installed headers include headers that are not installed:${missing}")
endif()

# 2. One translation unit per installed header, each including it alone.
set(project ${work}/consumer)
file(MAKE_DIRECTORY ${project})
set(sources "")
foreach(header ${headers})
  string(MAKE_C_IDENTIFIER ${header} name)
  file(WRITE ${project}/${name}.cc "#include \"${header}\"\n")
  list(APPEND sources ${name}.cc)
endforeach()
list(JOIN sources "\n  " source_list)
file(WRITE ${project}/CMakeLists.txt "cmake_minimum_required(VERSION 3.18)
project(hamal_installed_headers LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 17)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
find_package(hamal REQUIRED)
if(NOT TARGET hamal::testing OR NOT TARGET hamal::protocol)
  message(FATAL_ERROR \"the package offers no hamal::testing or hamal::protocol\")
endif()
add_library(installed_headers OBJECT
  ${source_list})
target_link_libraries(installed_headers PRIVATE hamal::hamal hamal::protocol hamal::testing)
")
set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run("configuring a project against the installed package"
    ${CMAKE_COMMAND} -S ${project} -B ${project}/build -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${prefix} ${launcher})
run("compiling each installed header alone" ${CMAKE_COMMAND} --build ${project}/build -j2)
message(STATUS "${count} installed headers: their includes are installed, each compiles alone")
