# hamal_rpgo_native (README.md here, "Kimera-RPGO"): Kimera-RPGO's library
# compiled from its checkout as its CMakeLists does (KimeraRPGO: src/*.cpp;
# rpgo_max_clique: the max clique finder), into this build directory,
# against the GTSAM 4.2a8 that CMakeLists.txt here found.
set(_rpgo_clique ${RPGO_SOURCE_DIR}/include/KimeraRPGO/max_clique_finder)
set(_rpgo_sources
  ${RPGO_SOURCE_DIR}/src/GenericSolver.cpp
  ${RPGO_SOURCE_DIR}/src/RobustSolver.cpp
  ${RPGO_SOURCE_DIR}/src/Logger.cpp
  ${RPGO_SOURCE_DIR}/src/utils/GraphUtils.cpp
  ${_rpgo_clique}/findClique.cpp
  ${_rpgo_clique}/findCliqueHeu.cpp
  ${_rpgo_clique}/graphIO.cpp
  ${_rpgo_clique}/utils.cpp)
foreach(_f ${_rpgo_sources} ${RPGO_SOURCE_DIR}/include/KimeraRPGO/outlier/Pcm.h)
  if(NOT EXISTS ${_f})
    message(FATAL_ERROR "Kimera-RPGO harness: ${_f} not found: is RPGO_SOURCE_DIR Kimera-RPGO's "
                        "checkout?")
  endif()
endforeach()
message(STATUS "Kimera-RPGO harness: GTSAM ${GTSAM_VERSION} from ${RISAM_GTSAM_DIR}, "
               "Kimera-RPGO from ${RPGO_SOURCE_DIR}")
add_library(hamal_rpgo_upstream STATIC ${_rpgo_sources})
# SYSTEM: Kimera-RPGO's headers are not held to hamal's warnings.
target_include_directories(hamal_rpgo_upstream SYSTEM PUBLIC ${RPGO_SOURCE_DIR}/include)
target_link_libraries(hamal_rpgo_upstream PUBLIC gtsam)

add_executable(hamal_rpgo_native rpgo_native.cc)
target_link_libraries(hamal_rpgo_native PRIVATE hamal_rpgo_upstream hamal_robust_lib)
target_compile_options(hamal_rpgo_native PRIVATE -Wall -Wextra)
target_link_options(hamal_rpgo_native PRIVATE -Wl,--disable-new-dtags)
set_target_properties(hamal_rpgo_native PROPERTIES BUILD_RPATH "${_gtsam_libdir}")
