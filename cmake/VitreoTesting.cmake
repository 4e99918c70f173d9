# Helpers for tests and benchmarks, so every folder declares them the same way.
#
#   vitreo_add_test(<name> SOURCES a.cpp ... LIBS lib ... LABELS core ...)
#     A GoogleTest executable whose cases are discovered one CTest test each, with the labels of
#     the design guide (core, topology, scenes, protocol, drivers, vm, rig, render, instruments,
#     calibration, scoring, e2e, fuzz) so parts of the suite run alone: `ctest -L core`.
#
#   vitreo_add_benchmark(<name> SOURCES a.cpp ... LIBS lib ...)
#     A Google Benchmark executable placed in <build>/bench/, run by tools/bench.sh.

include(GoogleTest)
find_package(GTest REQUIRED)
if(VITREO_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

function(vitreo_add_test name)
  # ENVIRONMENT: one NAME=VALUE for every test of the executable (set with the labels below).
  cmake_parse_arguments(T "" "TIMEOUT;ENVIRONMENT" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT VITREO_BUILD_TESTS)
    return()
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  # ThreadSanitizer runs the threaded code 5-15 times slower (a session test that loads cases on its
  # loader thread takes over 10 minutes there); its preset is run by hand, not in CI.
  if(VITREO_TSAN)
    math(EXPR T_TIMEOUT "${T_TIMEOUT} * 3")
  endif()
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gmock GTest::gtest_main vitreo_options)
  target_compile_definitions(${name} PRIVATE VITREO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  # A test may do less of the same work under a sanitizer, where it runs 10-20 times slower.
  if(VITREO_SANITIZE OR VITREO_TSAN)
    target_compile_definitions(${name} PRIVATE VITREO_SANITIZER_BUILD=1)
  endif()
  # Labels are set by a CTest include file that runs after discovery: passed through
  # gtest_discover_tests(PROPERTIES LABELS a;b ...) a list is split into bogus property/value pairs
  # (CMake 3.25), so a test with two labels silently lost the second one and its TIMEOUT.
  gtest_discover_tests(${name}
    TEST_LIST ${name}_TESTS
    PROPERTIES TIMEOUT ${T_TIMEOUT}
    DISCOVERY_TIMEOUT 120)
  set(_labels_file ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  set(_env "")
  if(T_ENVIRONMENT)
    set(_env " ENVIRONMENT \"${T_ENVIRONMENT}\"")
  endif()
  file(WRITE ${_labels_file}
    "if(${name}_TESTS)\n  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${T_LABELS}\"${_env})\nendif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${_labels_file})
endfunction()

function(vitreo_add_benchmark name)
  cmake_parse_arguments(B "" "" "SOURCES;LIBS" ${ARGN})
  if(NOT VITREO_BUILD_BENCHMARKS)
    return()
  endif()
  add_executable(${name} ${B_SOURCES})
  target_link_libraries(${name} PRIVATE ${B_LIBS} benchmark::benchmark benchmark::benchmark_main vitreo_options)
  target_compile_definitions(${name} PRIVATE VITREO_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bench)
endfunction()
