// A built-in method file under another name, for the tests of experiments/ (which know the
// source folder as STIFFBENCH_SOURCE_DIR).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace stiffbench::testing_support {

// methods/METHOD.toml copied under the method name `name` into a folder of this process's under
// the temporary directory (a method file given by path, as a user's would be); returns its path.
inline std::string renamed_method_file(const std::string& method, const std::string& name) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("stiffbench_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ifstream in(fs::path(STIFFBENCH_SOURCE_DIR) / "methods" / (method + ".toml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const std::string key = "name = \"" + method + "\"";
  const auto at = toml.find(key);
  if (at == std::string::npos) throw std::logic_error("methods/" + method + ".toml has no " + key);
  toml.replace(at, key.size(), "name = \"" + name + "\"");
  const fs::path path = dir / (name + ".toml");
  std::ofstream(path) << toml;
  return path.string();
}

}  // namespace stiffbench::testing_support
