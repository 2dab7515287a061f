# The instruction set Parallax is compiled for, and the workaround for a GCC 12 code-generation
# fault that AVX-512 tuning exposes (docs/portable-build.md).
#
# Default: -march=${PARALLAX_ARCH} (x86-64-v3: AVX2, FMA, BMI2) on x86-64, the compiler's own
# default elsewhere. PARALLAX_NATIVE=ON builds for the build machine (-march=native) instead.
include(CheckCXXCompilerFlag)

# Whether the build targets x86-64 (also read by tools/wide_constant_fault/CMakeLists.txt for
# the reproducer).
set(PARALLAX_X86_64 FALSE)
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(PARALLAX_X86_64 TRUE)
endif()

function(parallax_set_instruction_set)
  if(PARALLAX_NATIVE)
    set(arch_flag -march=native)
  elseif(PARALLAX_X86_64 AND PARALLAX_ARCH)
    set(arch_flag -march=${PARALLAX_ARCH})
  endif()
  if(arch_flag)
    add_compile_options(${arch_flag})
    message(STATUS "Parallax: compiling for ${arch_flag}")
  endif()

  # GCC 12 turns a 32- or 64-byte block copy of constant data whose upper words are zero into a
  # broadcast of its first word ({{1, 1}, {0, 0}} stored as four 1.0s) whenever by-pieces moves
  # are 256 bits wide, as AVX-512 tuning (and -march=native on such CPUs) makes them. Capping
  # by-pieces moves and stores at 128 bits keeps every such constant a complete 128-bit one,
  # which that code path handles correctly. tools/wide_constant_fault/ holds the reproducer and
  # its regression test.
  if(PARALLAX_X86_64 AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU"
     AND CMAKE_CXX_COMPILER_VERSION VERSION_GREATER_EQUAL 12)
    check_cxx_compiler_flag("-mmove-max=128 -mstore-max=128" PARALLAX_HAS_MOVE_MAX)
    if(PARALLAX_HAS_MOVE_MAX)
      add_compile_options(-mmove-max=128 -mstore-max=128)
    endif()
  endif()
endfunction()
