# Precompiled headers for the library's own targets: the system headers
# nearly every translation unit parses (Eigen's Core and SparseCore, the standard library, and in
# the experiments and CLI libraries nlohmann/json and CLI11) are parsed once per target instead of
# once per file. PRIVATE only: nothing reaches the exported targets of the installed package, and
# a consumer's own files are compiled without them. STIFFBENCH_PCH=OFF turns them off (e.g. to
# check that every file includes what it uses).
#
# ccache and PCH: GCC reads the .gch beside cmake_pch.hxx (included with -include), which ccache
# hashes; it caches such compiles only with sloppiness pch_defines,time_macros, and the .gch is
# written just before the files that use it, so include_file_mtime,include_file_ctime too (the
# ccache manual, "Precompiled headers"). When the compiler launcher is ccache, the launcher is
# wrapped in `cmake -E env CCACHE_SLOPPINESS=...` for stiffbench's own targets (ccache 4.7 has no
# key=value arguments); otherwise every PCH compile would be a ccache miss.
option(STIFFBENCH_PCH "Precompile the common system headers of the library targets" ON)

if(STIFFBENCH_PCH AND CMAKE_CXX_COMPILER_LAUNCHER MATCHES "ccache")
  set(_sb_sloppiness pch_defines,time_macros,include_file_mtime,include_file_ctime)
  if(DEFINED ENV{CCACHE_SLOPPINESS} AND NOT "$ENV{CCACHE_SLOPPINESS}" STREQUAL "")
    set(_sb_sloppiness "$ENV{CCACHE_SLOPPINESS},${_sb_sloppiness}")
  endif()
  set(CMAKE_CXX_COMPILER_LAUNCHER ${CMAKE_COMMAND} -E env CCACHE_SLOPPINESS=${_sb_sloppiness}
                                  ${CMAKE_CXX_COMPILER_LAUNCHER})
endif()

set(STIFFBENCH_PCH_COMMON <algorithm> <atomic> <chrono> <cmath> <complex> <functional> <map>
                          <memory> <optional> <set> <stdexcept> <string> <utility> <vector>
                          <Eigen/Core> <Eigen/SparseCore>)

# stiffbench_precompile(TARGET [HEADER...]): the common headers plus HEADERs, for TARGET's own
# sources; generated sources (embedded data, the revision) are skipped.
function(stiffbench_precompile target)
  if(NOT STIFFBENCH_PCH)
    return()
  endif()
  target_precompile_headers(${target} PRIVATE ${STIFFBENCH_PCH_COMMON} ${ARGN})
  # GCC 12 reports its middle-end warnings (-Warray-bounds, -Wstringop-overflow/-overread) in
  # libstdc++'s std::string code inlined into ours when the headers come from a PCH (the same
  # files compile without a warning when the headers are parsed: the system-header status of
  # those locations is lost), the false positives of GCC bug 105651 that -Wno-restrict answers.
  target_compile_options(${target} PRIVATE
                         "$<$<CXX_COMPILER_ID:GNU>:-Wno-array-bounds;-Wno-stringop-overflow;-Wno-stringop-overread>")
  get_target_property(_sources ${target} SOURCES)
  foreach(_src IN LISTS _sources)
    if(_src MATCHES "/generated/")
      set_source_files_properties(${_src} PROPERTIES SKIP_PRECOMPILE_HEADERS ON)
    endif()
  endforeach()
endfunction()
