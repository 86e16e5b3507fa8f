// Helpers of the tests that run the real stiffbench binary (tests/cli/; STIFFBENCH_BIN is defined
// for every test executable): run it with captured output and exit code, read a file whole, and
// name a fresh per-process scratch folder (the last two are used outside tests/cli/ as well).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace stiffbench::testing_support {

struct CliOutcome {
  int code = -1;  // the exit code; -1 when the binary did not exit normally
  std::string out, err;
};

// 's' quoted for the shell.
inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `stiffbench ARGS` through the shell (ARGS is shell text: quote paths with spaces), in
// `cwd` when given (relative output paths land there), with stdin from /dev/null.
inline CliOutcome run_cli(const std::string& args, const std::filesystem::path& cwd = {}) {
  const auto err_file =
      std::filesystem::temp_directory_path() / ("stiffbench_cli_err_" + std::to_string(::getpid()));
  std::string cmd = std::string(STIFFBENCH_BIN) + " " + args + " 2>" +
                    shell_quote(err_file.string()) + " </dev/null";
  if (!cwd.empty()) cmd = "cd " + shell_quote(cwd.string()) + " && " + cmd;
  CliOutcome o;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return o;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) o.out.append(buf.data(), n);
  const int status = ::pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream f(err_file);
  o.err.assign(std::istreambuf_iterator<char>(f), {});
  std::filesystem::remove(err_file);
  return o;
}

// The bytes of a file ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

// TMP/stiffbench_PREFIX_NAME_PID, removed if it exists (not created): per process, so
// concurrent test processes do not collide.
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() /
                 ("stiffbench_" + prefix + "_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  return d;
}

}  // namespace stiffbench::testing_support
