// The fuzzed entry points: each takes arbitrary bytes, feeds them to one parser of
// user input and returns normally when the parser either accepts the input or refuses it with
// BadInput. Anything else (another exception, a crash, a sanitizer report, a broken invariant
// checked here) is a defect. The libFuzzer mains (fuzz_*.cpp) call these; so does
// tests/experiments/test_fuzz_regressions.cpp, on the seed corpus and on every input a fuzz
// run ever found (fuzz/regressions/), in the normal g++ build.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace stiffbench::fuzz {

// `--param` lines ("key=value" per line) against declared parameters of every type.
void params_one(std::string_view data);
// A spec file (experiments/framework/spec_file.*) with this text.
void spec_file_one(std::string_view data);
// The CSV readers of `plot` and `merge` / `run --resume` (experiments/output/csv.*).
void csv_one(std::string_view data);
// A method file (integrators/method_file.*) with this text. Defined in method_file_target.cpp,
// which needs the integrator library (scripts/fuzz.sh compiles core/ and integrators/ for it).
void method_file_one(std::string_view data);

// Throws std::logic_error: a broken invariant found by a target.
[[noreturn]] void fail(const char* what);

}  // namespace stiffbench::fuzz
