# Install test: installs the quadify build into a temporary prefix, then configures, builds and
# runs examples/consumer (a separate project using find_package(quadify)) against that prefix.
# Run by CTest (tests/CMakeLists.txt) as
#   cmake -D QUADIFY_BUILD_DIR=<build> -D QUADIFY_SOURCE_DIR=<source> -D WORK_DIR=<scratch>
#         -D GENERATOR=<generator> -D CXX_COMPILER=<compiler> [-D BUILD_TYPE=<type>]
#         [-D MESH=<closed genus-0 OBJ>] -P consumer_test.cmake
# Fails (FATAL_ERROR) when any step fails or the printed counts differ from the OBJ's v/f lines.
cmake_minimum_required(VERSION 3.20)

foreach(var QUADIFY_BUILD_DIR QUADIFY_SOURCE_DIR WORK_DIR GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "consumer_test: -D ${var}=... is required")
  endif()
endforeach()
if(NOT BUILD_TYPE)
  set(BUILD_TYPE Release)
endif()

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer_test: ${what} failed (${rc})\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
run_step("install" "${CMAKE_COMMAND}" --install "${QUADIFY_BUILD_DIR}" --prefix "${prefix}")
foreach(installed include/libcore/mesh.h include/libquadex/quad_metrics.h)
  if(NOT EXISTS "${prefix}/${installed}")
    message(FATAL_ERROR "consumer_test: ${installed} was not installed")
  endif()
endforeach()

run_step("configure consumer" "${CMAKE_COMMAND}" -S "${QUADIFY_SOURCE_DIR}/examples/consumer"
         -B "${WORK_DIR}/build" -G "${GENERATOR}" "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
         "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}" "-DCMAKE_PREFIX_PATH=${prefix}")
run_step("build consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")

# The mesh: tests/data/cube.obj, or a small octahedron of our own when it is absent.
if(NOT MESH OR NOT EXISTS "${MESH}")
  set(MESH "${WORK_DIR}/octahedron.obj")
  file(WRITE "${MESH}" "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
                       "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n")
endif()
file(STRINGS "${MESH}" v_lines REGEX "^v ")
file(STRINGS "${MESH}" f_lines REGEX "^f ")
list(LENGTH v_lines n_v)
list(LENGTH f_lines n_f)

run_step("run consumer" "${WORK_DIR}/build/quadify_consumer" "${MESH}")
string(STRIP "${step_output}" printed)
# A closed genus-0 triangle mesh: χ = 2, no quads.
set(expected "${n_v} vertices ${n_f} faces 0 quads chi 2 genus 0")
if(NOT printed STREQUAL expected)
  message(FATAL_ERROR "consumer_test: ${MESH}: printed '${printed}', expected '${expected}'")
endif()
message(STATUS "consumer_test: ${MESH}: ${printed}")
