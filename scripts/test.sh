#!/usr/bin/env bash
# All tests: install dependencies, build, run ctest; then the same suite built with
# AddressSanitizer + UndefinedBehaviorSanitizer. Set STIFFBENCH_SKIP_SANITIZE=1 to skip the
# second build during local iteration (CI always runs both).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
jobs="$(nproc 2>/dev/null || echo 2)"
"$root/scripts/install-deps.sh"

echo "== Release build and tests"
"$root/scripts/build.sh" "$root/build"
(cd "$root/build" && ctest --output-on-failure -j "$jobs")

if [ "${STIFFBENCH_SKIP_SANITIZE:-0}" != "1" ]; then
  echo "== ASan + UBSan build and tests"
  CMAKE_BUILD_TYPE=RelWithDebInfo "$root/scripts/build.sh" "$root/build-sanitize" \
    -DSTIFFBENCH_SANITIZE=ON -DSTIFFBENCH_BUILD_BENCH=OFF
  (cd "$root/build-sanitize" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --output-on-failure -j "$jobs")
fi
