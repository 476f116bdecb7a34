# Embedded build profile, included right after project(keepless) through
# CMAKE_PROJECT_keepless_INCLUDE (see the `embedded` preset). The board
# libraries keepless::solver and keepless::core are compiled for size and
# without exceptions or RTTI: the decision path reports errors as status enums
# and never needs either. Tests and tools keep the default flags; they link
# the embedded libraries, so the suite exercises exactly what a board runs.
# -funwind-tables: an allocation that fails while a Window or Sparsifier is
# built throws std::bad_alloc (std::length_error on 32-bit) from the C++
# runtime, which keepless_node and keepless_sparsify catch ("cannot
# allocate ...", exit 2). Without exceptions GCC gives 32-bit ARM code no
# unwind tables, and the unwinder calls std::terminate at the library's
# first frame (core_allocation_failure_test). aarch64 and x86-64 have the
# tables by default.
set(KEEPLESS_EMBEDDED_PROFILE ON)

# The targets do not exist yet here: apply the options once the top-level
# CMakeLists.txt has been processed. -Os follows -O3 of CMAKE_BUILD_TYPE on
# the command line, so it wins.
function(keepless_apply_embedded_profile)
  foreach(target keepless_solver keepless_core)
    if(NOT TARGET ${target})
      message(FATAL_ERROR "embedded profile: no target ${target}")
    endif()
    target_compile_options(${target} PRIVATE -Os -fno-exceptions -fno-rtti -funwind-tables)
  endforeach()
  message(STATUS "embedded profile: keepless_solver, keepless_core with -Os -fno-exceptions -fno-rtti -funwind-tables")
endfunction()
cmake_language(DEFER DIRECTORY ${CMAKE_SOURCE_DIR} CALL keepless_apply_embedded_profile)
