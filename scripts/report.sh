#!/usr/bin/env bash
# The main job: install dependencies, build the command-line program, and run `stiffbench report`
# on the default suite.
# Usage: scripts/report.sh [OUT_DIR] [--quick] [--force]     (default OUT_DIR: results; running
# it again with the same suite replaces the results, the other suite needs --force)
# Only the target `stiffbench` (the libraries and the CLI) is built: the tests and benchmarks
# are built by scripts/test.sh (scripts/build.sh builds every target). On a fresh configure the
# target compiles 109 translation units, the full build 202.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-results}"
shift || true
jobs="$(nproc 2>/dev/null || echo 2)"
"$root/scripts/install-deps.sh"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE="${CMAKE_BUILD_TYPE:-Release}" >/dev/null
cmake --build "$root/build" -j "$jobs" --target stiffbench
"$root/build/stiffbench" report --out "$out" "$@"
