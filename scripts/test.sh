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
echo "== stiffbench audit: every built-in method's claims (counts, orders, tableaux; exit 3 on a failed check)"
rm -rf "$root/build/audit"
start=$(date +%s)
if ! "$root/build/stiffbench" audit --out "$root/build/audit" \
    >"$root/build/audit.log" 2>&1; then
  tail -n 40 "$root/build/audit.log" >&2
  grep ',fail,' "$root/build/audit/audit.csv" >&2 || true
  exit 1
fi
echo "audit took $(( $(date +%s) - start )) s"
echo "== Function lengths: none in experiments/ or cli/ over 80 lines (the five longest)"
python3 "$root/scripts/function_lengths.py" -n 5 --max 80 $(find "$root/experiments" "$root/cli" -name '*.cpp' | sort)
echo "== Install check (cmake --install, examples/user_system with find_package, add_subdirectory)"
"$root/scripts/check-install.sh" "$root/build"
echo "== stiffbench report --quick --html (every experiment kind with its plot)"
rm -rf "$root/build/report-quick"
start=$(date +%s)
if ! "$root/build/stiffbench" report --quick --html --out "$root/build/report-quick" \
    2>"$root/build/report-quick.log"; then
  tail -n 30 "$root/build/report-quick.log" >&2
  exit 1
fi
echo "report --quick took $(( $(date +%s) - start )) s"
for kind in convergence local_error energy region stability work_precision; do
  if ! ls "$root/build/report-quick"/*/"$kind.png" >/dev/null 2>&1; then
    echo "report --quick wrote no $kind.png" >&2
    exit 1
  fi
done
echo "== report.html in headless Chromium (sections, plots, no console error, sorting, screenshot)"
"$root/scripts/check-html.sh" "$root/build/report-quick"
echo "== stiffbench profile stiff --quick --html, and profile.html in headless Chromium"
rm -rf "$root/build/profile-quick"
start=$(date +%s)
if ! "$root/build/stiffbench" profile stiff --quick --html --out "$root/build/profile-quick" \
    >"$root/build/profile-quick.log" 2>&1; then
  tail -n 30 "$root/build/profile-quick.log" >&2
  exit 1
fi
echo "profile stiff --quick took $(( $(date +%s) - start )) s"
"$root/scripts/check-html.sh" "$root/build/profile-quick" profile.html profile.md

# --- Determinism and fuzzing: the same command twice and 1 vs 2 threads give
# identical CSVs (about 20 s); the libFuzzer targets of fuzz/ built with clang (about a minute
# and a half) and run 30 s each on their seed corpus.
echo "== Determinism"
"$root/scripts/check-determinism.sh" "$root/build"
echo "== Fuzzing (30 s per target)"
start=$(date +%s)
"$root/scripts/fuzz.sh" "$root/build-fuzz"
echo "fuzzing took $(( $(date +%s) - start )) s"
# --- end of the determinism and fuzzing block

# --- Slurm smoke test (scripts/slurm-smoke.sh): a 4-task job array of
# suites/sweep_spring_chain.toml on a single-node Slurm started on localhost, merged
# and compared with the unsharded run (about 10 s). Without root (it installs packages and
# starts daemons) the same comparison with the 4 shards run locally.
echo "== Slurm smoke test"
if [ "$(id -u)" = 0 ]; then
  "$root/scripts/slurm-smoke.sh" "$root/build"
else
  "$root/scripts/slurm-smoke.sh" --local "$root/build"
fi
# --- end of the Slurm smoke block

if [ "${STIFFBENCH_SKIP_SANITIZE:-0}" != "1" ]; then
  echo "== ASan + UBSan build and tests"
  # Without precompiled headers: this build keeps the three GCC warnings the PCH build switches
  # off (cmake/pch.cmake) and checks that every file includes what it uses. -g1 (line tables,
  # all the sanitizers' stack traces need) instead of RelWithDebInfo's -g: full debug info made
  # this build about 40 % slower (radau5.cpp: 266 s against 187 s on a 2-core CI machine). -O1
  # (the level the ASan documentation recommends) instead of -O2: the heaviest files compile a
  # quarter to a third faster (radau5.cpp 141 s against 204 s, network.cpp 25 s against 37 s,
  # dirk.cpp 12 s against 18 s, one after the other on this machine).
  CMAKE_BUILD_TYPE=RelWithDebInfo "$root/scripts/build.sh" "$root/build-sanitize" \
    -DSTIFFBENCH_SANITIZE=ON -DSTIFFBENCH_BUILD_BENCH=OFF -DSTIFFBENCH_PCH=OFF \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
  (cd "$root/build-sanitize" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --output-on-failure -j "$jobs")
  # The whole main job under the sanitizers: every experiment kind, the library
  # references and the plots of `report --quick`, with LeakSanitizer reporting any leak at exit
  # (ASan's exit code 23 then fails this step; UBSan aborts on the first finding).
  echo "== Leak check: report --quick under ASan + UBSan"
  rm -rf "$root/build-sanitize/report-quick"
  start=$(date +%s)
  if ! ASAN_OPTIONS=detect_leaks=1:exitcode=23 UBSAN_OPTIONS=print_stacktrace=1 \
      "$root/build-sanitize/stiffbench" report --quick \
      --out "$root/build-sanitize/report-quick" 2>"$root/build-sanitize/report-quick.log"; then
    tail -n 60 "$root/build-sanitize/report-quick.log" >&2
    exit 1
  fi
  if grep -q "LeakSanitizer\|runtime error:" "$root/build-sanitize/report-quick.log"; then
    grep -A 30 "LeakSanitizer\|runtime error:" "$root/build-sanitize/report-quick.log" >&2
    exit 1
  fi
  echo "report --quick under ASan + UBSan: no leak, no error ($(( $(date +%s) - start )) s)"
fi
