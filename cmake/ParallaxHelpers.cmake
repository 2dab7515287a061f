# One library target per layer folder, with explicit link dependencies so that an
# upward include fails to link (COLMAP's COLMAP_ADD_LIBRARY habit).
#
#   parallax_add_library(NAME geometry DEPS parallax_math)
#   parallax_add_tests(NAME geometry DEPS parallax_geometry)
#
# Sources are the folder's *.cc files (recursively) other than *_test.cc. Each foo_test.cc
# becomes its own test executable <folder>_foo_test (so one broken test cannot stop another
# from building), registered case by case with CTest through gtest_discover_tests.

function(parallax_add_library)
  cmake_parse_arguments(ARG "" "NAME" "DEPS;EXCLUDE" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cc)
  list(FILTER sources EXCLUDE REGEX "_test\\.cc$")
  list(FILTER sources EXCLUDE REGEX "_fuzz\\.cc$")
  foreach(excluded ${ARG_EXCLUDE})
    list(FILTER sources EXCLUDE REGEX "${excluded}")
  endforeach()
  set(target parallax_${ARG_NAME})
  if(NOT sources)
    # A layer with headers only (or none yet).
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
    return()
  endif()
  add_library(${target} STATIC ${sources})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS})
  parallax_use_precompiled_headers(${target} library)
endfunction()

function(parallax_add_tests)
  cmake_parse_arguments(ARG "" "NAME" "DEPS" ${ARGN})
  if(NOT PARALLAX_BUILD_TESTS)
    return()
  endif()
  file(GLOB_RECURSE tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*_test.cc)
  foreach(test_source ${tests})
    get_filename_component(test_name ${test_source} NAME_WE)
    set(target ${ARG_NAME}_${test_name})
    add_executable(${target} ${test_source})
    target_link_libraries(${target} PRIVATE ${ARG_DEPS} parallax_test_main GTest::gtest GTest::gmock)
    parallax_use_precompiled_headers(${target} test)
    gtest_discover_tests(${target}
      DISCOVERY_TIMEOUT 60
      PROPERTIES ENVIRONMENT "PARALLAX_BINARY=${PROJECT_BINARY_DIR}/parallax")
  endforeach()
endfunction()
