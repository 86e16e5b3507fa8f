#!/usr/bin/env bash
# Build times: prints
#  1. the clean Release build of the libraries and the CLI (the target `stiffbench`, which
#     depends on every library; tests and benchmarks apart) in a fresh build folder, ccache off
#     (CCACHE_DISABLE=1): wall and user+sys CPU seconds;
#  2. one user translation unit that includes <stiffbench/stiffbench.hpp>: the build is installed
#     into a temporary prefix, examples/user_system (the install check's program) is configured
#     against it with find_package (Release, so the flags the installed package gives), and its
#     main.cpp compile command (from compile_commands.json) is run REPS times: the median wall and
#     user+sys CPU seconds. With --report, GCC's -ftime-report phases of one more compile.
# CPU seconds (user+sys) do not depend much on what else runs on the machine; wall seconds do.
# Usage: scripts/build-times.sh [--tree SRC] [--build DIR] [--jobs N] [--reps N] [--tu FILE]
#                               [--report]
#   --tree SRC   the source tree to measure (default: this one), e.g. a `git worktree` of main
#   --build DIR  skip step 1 and use DIR, an already built folder of SRC, for step 2
#   --jobs N     parallel jobs of step 1 (default: nproc)
#   --reps N     compiles of the user unit (default 3)
#   --tu FILE    the user unit, relative to examples/user_system/ (default main.cpp)
# Exit 0 when both measurements ran, 1 otherwise; temporary folders are removed at exit.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tree="$root"
build=""
jobs="$(nproc 2>/dev/null || echo 2)"
reps=3
tu=main.cpp
report=0
while [ $# -gt 0 ]; do
  case "$1" in
    --tree) tree="$(cd "$2" && pwd)"; shift 2 ;;
    --build) build="$(cd "$2" && pwd)"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --reps) reps="$2"; shift 2 ;;
    --tu) tu="$2"; shift 2 ;;
    --report) report=1; shift ;;
    *) echo "build-times: unknown argument '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
case "$reps" in '' | *[!0-9]* | 0) echo "build-times: --reps '$reps' is not a positive integer" >&2; exit 2 ;; esac
case "$jobs" in '' | *[!0-9]* | 0) echo "build-times: --jobs '$jobs' is not a positive integer" >&2; exit 2 ;; esac

tmp="$(mktemp -d "${TMPDIR:-/tmp}/stiffbench-build-times.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
log="$tmp/log"
fail() {
  echo "build-times: FAILED: $*" >&2
  [ -s "$log" ] && tail -n 30 "$log" >&2
  exit 1
}
# `/usr/bin/time -f '%e %U %S'` output → "W s wall, C s CPU (user+sys)"
fmt_time() { awk '{ printf "%.1f s wall, %.1f s CPU (user %.1f + sys %.1f)", $1, $2 + $3, $2, $3 }' "$1"; }

export CCACHE_DISABLE=1
echo "build-times: tree $tree ($(git -C "$tree" rev-parse --short HEAD 2>/dev/null || echo '?')," \
  "$(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg))"

# --- 1. clean build of the libraries and the CLI
if [ -z "$build" ]; then
  build="$tmp/build"
  cmake -S "$tree" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$log" 2>&1 || fail "configuring $tree"
  echo "build-times: clean build (cmake --build -j $jobs --target stiffbench, ccache off) ..."
  /usr/bin/time -f '%e %U %S' -o "$tmp/clean.time" \
    cmake --build "$build" -j "$jobs" --target stiffbench >"$log" 2>&1 || fail "the clean build"
  echo "build-times: clean build: $(fmt_time "$tmp/clean.time")"
else
  echo "build-times: clean build skipped (--build $build)"
fi

# --- 2. one user translation unit against the installed package
prefix="$tmp/prefix"
cmake --install "$build" --prefix "$prefix" >"$log" 2>&1 || fail "cmake --install $build"
example="$tmp/user_system"
cp -r "$tree/examples/user_system" "$example"
[ -f "$example/$tu" ] || fail "no examples/user_system/$tu"
cmake -S "$example" -B "$tmp/example-build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >"$log" 2>&1 ||
  fail "configuring examples/user_system against the installed package"
command="$(python3 - "$tmp/example-build/compile_commands.json" "$example/$tu" <<'EOF'
import json, os, sys
for e in json.load(open(sys.argv[1])):
    if os.path.realpath(e["file"]) == os.path.realpath(sys.argv[2]):
        print(e["command"])
EOF
)"
[ -n "$command" ] || fail "no compile command for $tu in compile_commands.json"
echo "build-times: user unit: $command"
cd "$tmp/example-build"
for i in $(seq "$reps"); do
  # shellcheck disable=SC2086  # the command line is split as the build tool would
  /usr/bin/time -f '%e %U %S' -o "$tmp/tu.$i" $command >"$log" 2>&1 || fail "compiling $tu"
done
# The median rep by CPU seconds.
median="$(for i in $(seq "$reps"); do awk -v f="$tmp/tu.$i" '{ print $2 + $3, f }' "$tmp/tu.$i"; done |
  sort -n | awk -v n="$reps" 'NR == int((n + 1) / 2) { print $2 }')"
echo "build-times: user unit ($tu, median of $reps): $(fmt_time "$median")"
if [ "$report" = 1 ]; then
  # shellcheck disable=SC2086
  $command -ftime-report 2>"$tmp/report" >/dev/null || fail "compiling $tu with -ftime-report"
  echo "build-times: -ftime-report, the largest phases (usr s):"
  grep -E '^ (phase|template instantiation|parser|preprocessing)' "$tmp/report" |
    awk -F: '{ split($2, a, " "); printf "  %6.2f  %s\n", a[1], $1 }' | sort -rn | head -n 8
fi
