# Run at install time (cmake/install.cmake): in every installed header under DIR (the prefix's
# include/stiffbench), the project's own includes "core/...", "models/...", "integrators/..." and
# "experiments/..." and "cli/..." become "stiffbench/core/..." and so on, so that a consumer needs only
# <prefix>/include on its include path and its own folders named core/ or models/ cannot collide
# with stiffbench's headers.
file(GLOB_RECURSE _headers "${DIR}/*.hpp")
foreach(_h IN LISTS _headers)
  file(READ "${_h}" _text)
  string(REGEX REPLACE "#include \"(core|models|integrators|experiments|cli)/" "#include \"stiffbench/\\1/"
         _new "${_text}")
  if(NOT _new STREQUAL _text)
    file(WRITE "${_h}" "${_new}")
  endif()
endforeach()
