# Precompiled headers for the GCC build (PARALLAX_PRECOMPILED_HEADERS): the standard library and
# Eigen, which nearly every file includes, parsed once per build instead of once per file (2 to
# 3 s of each file's 5 to 15 s here), and GoogleTest once more for the tests.
#
# A precompiled header is only used by files compiled with the flags it was made with, and
# libraries (-fPIC) and executables (-fPIE) differ, so there are three: one for the layer
# libraries, one for executables, one for test executables. Each is made once, by a host
# target of that kind, and the others reuse it (REUSE_FROM). GCC skips a header it cannot use
# and parses the listed headers as text instead, with a warning (-Winvalid-pch): a mismatch
# costs time, never correctness.

set(PARALLAX_PRECOMPILED_HEADERS_LIST
    <algorithm> <array> <atomic> <cmath> <cstdint> <cstring> <filesystem> <functional> <map>
    <memory> <mutex> <optional> <set> <sstream> <string> <unordered_map> <utility> <vector>
    <Eigen/Core> <Eigen/Geometry>)

function(parallax_add_precompiled_header_hosts)
  if(NOT PARALLAX_PRECOMPILED_HEADERS)
    return()
  endif()
  set(hosts ${PROJECT_SOURCE_DIR}/cmake/pch)
  add_library(parallax_pch_library OBJECT ${hosts}/empty.cc)
  target_link_libraries(parallax_pch_library PRIVATE Eigen3::Eigen)
  target_precompile_headers(parallax_pch_library PRIVATE ${PARALLAX_PRECOMPILED_HEADERS_LIST})

  add_executable(parallax_pch_executable ${hosts}/main.cc)
  target_link_libraries(parallax_pch_executable PRIVATE Eigen3::Eigen)
  target_precompile_headers(parallax_pch_executable PRIVATE ${PARALLAX_PRECOMPILED_HEADERS_LIST})

  if(PARALLAX_BUILD_TESTS)
    add_executable(parallax_pch_test ${hosts}/main.cc)
    target_link_libraries(parallax_pch_test PRIVATE Eigen3::Eigen GTest::gtest)
    target_precompile_headers(parallax_pch_test PRIVATE ${PARALLAX_PRECOMPILED_HEADERS_LIST}
                              <gtest/gtest.h>)
  endif()
endfunction()

# KIND is library, executable or test: which host's header `target` reuses.
function(parallax_use_precompiled_headers target kind)
  if(PARALLAX_PRECOMPILED_HEADERS)
    target_precompile_headers(${target} REUSE_FROM parallax_pch_${kind})
  endif()
endfunction()
