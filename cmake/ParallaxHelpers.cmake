# One library target per layer folder, with explicit link dependencies so that an
# upward include fails to link (COLMAP's COLMAP_ADD_LIBRARY habit).
#
#   parallax_add_library(NAME geometry SRCS a.cc b.cc DEPS parallax_math)
#   parallax_add_tests(NAME geometry SRCS a_test.cc DEPS parallax_geometry)
#
# Tests of one folder are linked into one executable (link time on 2 cores matters)
# and registered with CTest case by case through gtest_discover_tests.

function(parallax_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SRCS;DEPS" ${ARGN})
  set(target parallax_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SRCS})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS})
endfunction()

function(parallax_add_tests)
  cmake_parse_arguments(ARG "" "NAME" "SRCS;DEPS" ${ARGN})
  if(NOT PARALLAX_BUILD_TESTS)
    return()
  endif()
  set(target ${ARG_NAME}_test)
  add_executable(${target} ${ARG_SRCS})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} parallax_test_main GTest::gtest GTest::gmock)
  gtest_discover_tests(${target}
    DISCOVERY_TIMEOUT 60
    PROPERTIES ENVIRONMENT "PARALLAX_BINARY=$<TARGET_FILE:parallax>")
endfunction()
