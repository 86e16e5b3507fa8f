#!/usr/bin/env bash
# Checks stiffbench as a package a separate project uses:
#  1. `cmake --install BUILD_DIR` into a fresh temporary prefix;
#  2. examples/user_system configured against it with find_package (CMAKE_PREFIX_PATH=prefix),
#     built (Release) and run in a temporary working folder; both CSVs must exist with data rows
#     (and both PNGs when gnuplot is on PATH); then examples/user_method (a user's own system and
#     own Integrator class, not registered, through convergence, stability, energy and
#     work-precision), which checks its method's order and stability limit against theory, and
#     its system's additive split through explicit_part_view/implicit_part_view, an ars232 run
#     and the additive order conditions (all from the public header);
#  3. a tiny add_subdirectory consumer written on the fly (its own project, CMAKE_BUILD_TYPE
#     Debug, an executable that creates a model by name and takes one rk4 step) is configured,
#     and its CMakeCache must show STIFFBENCH_BUILD_TESTS, STIFFBENCH_BUILD_BENCH and
#     STIFFBENCH_WERROR OFF and CMAKE_BUILD_TYPE Debug. Building it compiles every library
#     again in Debug (several minutes on 2 cores), so it is only built with
#     STIFFBENCH_CHECK_SUBDIR_BUILD=1.
# Usage: scripts/check-install.sh [BUILD_DIR]   (default: build/, already built)
# Exit 0 when every check passes, 1 otherwise; every temporary folder is removed at exit.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" 2>/dev/null && pwd)" || {
  echo "check-install: no build folder '${1:-$root/build}' (build it first: scripts/build.sh)" >&2
  exit 1
}
jobs="$(nproc 2>/dev/null || echo 2)"
start=$(date +%s)

tmp="$(mktemp -d "${TMPDIR:-/tmp}/stiffbench-check-install.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
log="$tmp/log"

fail() {
  echo "check-install: FAILED: $*" >&2
  if [ -s "$log" ]; then
    echo "--- last lines of the step's output:" >&2
    tail -n 30 "$log" >&2
  fi
  exit 1
}

# Rows after the header line that are not empty.
data_rows() { tail -n +2 "$1" | grep -c . || true; }

# --- 1. install into a temporary prefix
prefix="$tmp/prefix"
echo "check-install: installing $build into a temporary prefix"
cmake --install "$build" --prefix "$prefix" >"$log" 2>&1 || fail "cmake --install $build"
for f in include/stiffbench/stiffbench.hpp lib/cmake/stiffbench/stiffbenchConfig.cmake \
         lib/cmake/stiffbench/stiffbenchConfigVersion.cmake bin/stiffbench; do
  [ -e "$prefix/$f" ] || fail "the install has no $f"
done
ls "$prefix"/share/stiffbench/plots/*.gp >/dev/null 2>&1 || fail "the install has no plots/*.gp"

# --- 2. examples/user_system against the installed package
example="$root/examples/user_system"
[ -f "$example/CMakeLists.txt" ] || fail "no $example/CMakeLists.txt"
echo "check-install: building examples/user_system with find_package(stiffbench)"
cmake -S "$example" -B "$tmp/example-build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >"$log" 2>&1 ||
  fail "configuring examples/user_system against the installed package"
cmake --build "$tmp/example-build" -j "$jobs" >"$log" 2>&1 || fail "building examples/user_system"
run="$tmp/run"
mkdir -p "$run"
echo "check-install: running user_system"
(cd "$run" && "$tmp/example-build/user_system" "$run/out") >"$log" 2>&1 ||
  fail "user_system exited with status $?"
for csv in convergence/convergence.csv work_precision/work_precision.csv; do
  [ -s "$run/out/$csv" ] || fail "user_system wrote no $csv"
  rows=$(data_rows "$run/out/$csv")
  [ "$rows" -gt 0 ] || fail "$csv has a header but no data rows"
  echo "check-install:   $csv: $rows rows"
done
if command -v gnuplot >/dev/null 2>&1; then
  for png in convergence/convergence.png work_precision/work_precision.png; do
    [ -s "$run/out/$png" ] || fail "gnuplot is installed but user_system wrote no $png"
  done
  echo "check-install:   convergence.png and work_precision.png written"
else
  echo "check-install:   gnuplot not on PATH: PNGs not checked"
fi

# --- 2b. examples/user_method: a user's own system and own integrator (not registered by name)
# through convergence, stability, energy and work-precision with the one-call functions; the
# program checks ralston3's order (3) and stability limit (sqrt(3)/50), and its system's additive
# split (f_E + f_I = f through the part views, ars232's order 2 from h = 0.1, ars232's additive
# order conditions), and exits 1 otherwise.
example="$root/examples/user_method"
echo "check-install: building examples/user_method with find_package(stiffbench)"
cmake -S "$example" -B "$tmp/method-build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >"$log" 2>&1 ||
  fail "configuring examples/user_method against the installed package"
cmake --build "$tmp/method-build" -j "$jobs" >"$log" 2>&1 || fail "building examples/user_method"
echo "check-install: running user_method"
(cd "$run" && "$tmp/method-build/user_method" "$run/method") >"$log" 2>&1 ||
  fail "user_method exited with status $? (or its order/stability check failed)"
for csv in convergence/convergence.csv stability/stability.csv energy/energy_summary.csv \
           work_precision/work_precision.csv; do
  [ -s "$run/method/$csv" ] || fail "user_method wrote no $csv"
  grep -q ralston3 "$run/method/$csv" || fail "$csv has no row of the user's ralston3"
done
echo "check-install:   user_method: $(tail -n 1 "$log")"

# --- 3. add_subdirectory consumer: the parent keeps its build type, no tests, benchmarks or -Werror
consumer="$tmp/consumer"
mkdir -p "$consumer"
cat >"$consumer/CMakeLists.txt" <<EOF
cmake_minimum_required(VERSION 3.25)
project(consumer LANGUAGES CXX)
set(CMAKE_BUILD_TYPE Debug)
set(CMAKE_CXX_STANDARD 20)
add_subdirectory("$root" stiffbench)
add_executable(consumer main.cpp)
target_link_libraries(consumer PRIVATE stiffbench::stiffbench)
EOF
cat >"$consumer/main.cpp" <<'EOF'
// One rk4 step of a model created by name, through the public header.
#include <iostream>
#include <stiffbench/stiffbench.hpp>

int main() {
  using namespace stiffbench;
  auto model = model_registry().create("harmonic_oscillator", Params{});
  auto rk4 = integrator_registry().create("rk4", Params{});
  Vec y = model->initial_state();
  rk4->reset(*model, 0.0, y);
  model->reset_counters();  // f evaluations are counted by the system, not by step()
  SolveStats stats;
  const Status s = rk4->step(*model, 0.0, y, 0.01, stats);
  std::cout << to_string(s) << ", " << model->counters().f_evals << " f evaluations, y = "
            << y.transpose() << "\n";
  return s == Status::ok && model->counters().f_evals == 4 && y.allFinite() ? 0 : 1;
}
EOF
echo "check-install: configuring an add_subdirectory consumer (Debug)"
env -u CMAKE_BUILD_TYPE cmake -S "$consumer" -B "$consumer/build" -G "Unix Makefiles" >"$log" 2>&1 ||
  fail "configuring the add_subdirectory consumer"
cache="$consumer/build/CMakeCache.txt"
cache_value() { sed -n "s/^$1:[A-Z]*=//p" "$cache"; }
for opt in STIFFBENCH_BUILD_TESTS STIFFBENCH_BUILD_BENCH STIFFBENCH_WERROR; do
  v="$(cache_value "$opt")"
  [ "$v" = OFF ] || fail "add_subdirectory consumer: $opt is '$v' in its CMakeCache, expected OFF"
done
# The consumer's set(CMAKE_BUILD_TYPE Debug) is a normal variable: stiffbench must not have put
# another value in the cache (the entry stays empty) nor compiled itself with other flags.
bt="$(cache_value CMAKE_BUILD_TYPE)"
[ -z "$bt" ] || [ "$bt" = Debug ] ||
  fail "add_subdirectory consumer: CMAKE_BUILD_TYPE is '$bt' in its CMakeCache, expected Debug"
flags="$consumer/build/stiffbench/core/CMakeFiles/stiffbench_core.dir/flags.make"
[ -f "$flags" ] || fail "add_subdirectory consumer: no $flags"
grep -q '^CXX_FLAGS.* -g' "$flags" && ! grep -q '^CXX_FLAGS.*-O[23]' "$flags" ||
  fail "add_subdirectory consumer: stiffbench_core is not compiled with the Debug flags:" \
    "$(grep '^CXX_FLAGS' "$flags")"
if grep -q -- '-Werror' "$flags"; then fail "add_subdirectory consumer: stiffbench has -Werror"; fi
echo "check-install:   tests, bench and -Werror OFF; stiffbench compiled with the parent's Debug flags"
if [ "${STIFFBENCH_CHECK_SUBDIR_BUILD:-0}" = 1 ]; then
  echo "check-install: building the add_subdirectory consumer (compiles stiffbench in Debug)"
  cmake --build "$consumer/build" --target consumer -j "$jobs" >"$log" 2>&1 ||
    fail "building the add_subdirectory consumer"
  "$consumer/build/consumer" >"$log" 2>&1 || fail "the add_subdirectory consumer's rk4 step"
  echo "check-install:   consumer: $(cat "$log")"
else
  echo "check-install:   consumer not built (STIFFBENCH_CHECK_SUBDIR_BUILD=1 builds it;" \
    "it compiles every library again in Debug)"
fi

echo "check-install: OK in $(( $(date +%s) - start )) s"
