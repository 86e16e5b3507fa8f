// The built-in method files (methods/*.toml at the repository root) compiled into the library:
// a C++ file generated at build time by cmake/embed_files.cmake (integrators/CMakeLists.txt)
// holds each file's name and text. built_in_methods() (integrators/method_file.hpp) parses them
// once; nothing else reads them.
#pragma once

#include <string_view>
#include <utility>
#include <vector>

namespace stiffbench {

// (file name, file text) of every methods/*.toml, sorted by file name.
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_method_files();

}  // namespace stiffbench
