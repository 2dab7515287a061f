# Precompiled headers (PARALLAX_PRECOMPILED_HEADERS, on with GCC and clang): the standard
# library and Eigen, which nearly every file includes, parsed once per build instead of once per
# file (2 to 3 s of each file's 5 to 15 s here), and GoogleTest once more for the tests.
#
# A precompiled header is only used by files compiled with the flags it was made with, and
# libraries (-fPIC) and executables (-fPIE) differ, so there are three: one for the layer
# libraries, one for executables, one for test executables (and a fourth in the fuzzing build,
# fuzz/CMakeLists.txt). Each is made once, by a host target of that kind, and the others reuse
# it (REUSE_FROM). GCC skips a header it cannot use and parses the listed headers as text
# instead, with a warning (-Winvalid-pch): a mismatch costs time, never correctness. Clang
# refuses one made with other language options (a sanitizer) and fails the build instead;
# extra -D macros on the command line it accepts.

set(PARALLAX_PRECOMPILED_HEADERS_LIST
    <algorithm> <array> <atomic> <cmath> <cstdint> <cstring> <filesystem> <functional> <map>
    <memory> <mutex> <optional> <set> <sstream> <string> <unordered_map> <utility> <vector>
    <Eigen/Core> <Eigen/Geometry>)

# A host target of kind KIND (library, executable or test) that makes the precompiled header
# the targets of that kind reuse; OPTIONS are compile options it must share with them.
function(parallax_add_precompiled_header_host kind)
  cmake_parse_arguments(ARG "" "" "OPTIONS" ${ARGN})
  set(hosts ${PROJECT_SOURCE_DIR}/cmake/pch)
  set(headers ${PARALLAX_PRECOMPILED_HEADERS_LIST})
  set(libraries Eigen3::Eigen)
  if(kind MATCHES "^test")
    list(APPEND headers <gtest/gtest.h>)
    list(APPEND libraries GTest::gtest)
  endif()
  if(kind MATCHES "^library")
    add_library(parallax_pch_${kind} OBJECT ${hosts}/empty.cc)
  else()
    add_executable(parallax_pch_${kind} ${hosts}/main.cc)
  endif()
  target_link_libraries(parallax_pch_${kind} PRIVATE ${libraries})
  target_compile_options(parallax_pch_${kind} PRIVATE ${ARG_OPTIONS})
  target_precompile_headers(parallax_pch_${kind} PRIVATE ${headers})
endfunction()

function(parallax_add_precompiled_header_hosts)
  if(NOT PARALLAX_PRECOMPILED_HEADERS)
    return()
  endif()
  parallax_add_precompiled_header_host(library)
  parallax_add_precompiled_header_host(executable)
  if(PARALLAX_BUILD_TESTS)
    parallax_add_precompiled_header_host(test)
  endif()
endfunction()

# KIND is library, executable or test: which host's header `target` reuses. Called again for
# a target that already reuses one, it switches to the other.
function(parallax_use_precompiled_headers target kind)
  if(PARALLAX_PRECOMPILED_HEADERS)
    set_property(TARGET ${target} PROPERTY PRECOMPILE_HEADERS_REUSE_FROM parallax_pch_${kind})
    add_dependencies(${target} parallax_pch_${kind})
  endif()
endfunction()
