#!/usr/bin/env bash
# Fuzzing: builds the libFuzzer targets of fuzz/ with Debian's clang and runs each for
# FUZZ_SECONDS (default 30) on a copy of its seed corpus fuzz/corpus/TARGET. The parser targets
# (params, spec_file, csv) compile only the sources they need (core/params.cpp, the spec-file
# parser and its input checks, the CSV readers, the number formats); method_file needs the
# integrator library (a method file builds its integrator to check it), so its objects are
# core/ and integrators/ without the library references (SUNDIALS, GSL) and the registration.
# A crash leaves its input in BUILD/crash-TARGET-*; copy it to fuzz/regressions/TARGET/
# (tests/experiments/test_fuzz_regressions.cpp replays every file there) and fix.
# Usage: scripts/fuzz.sh [BUILD_DIR]   (default build-fuzz)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/build-fuzz}"
seconds="${FUZZ_SECONDS:-30}"
mkdir -p "$out"
cxx="${FUZZ_CXX:-clang++}"
# toml++ as the real build uses it: Debian's shared library (its CMake config's definitions), not
# the header-only parser, whose debug assertions abort on inputs the library refuses cleanly.
flags=(-std=c++20 -O1 -g -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -Wno-pass-failed
  -DTOML_HEADER_ONLY=0 -DTOML_SHARED_LIB=1 -I"$root" -isystem /usr/include/eigen3)
# The shared sources, compiled once (about a minute on 2 cores); then one small main each.
srcs=(core/params.cpp experiments/framework/spec_file.cpp experiments/output/format.cpp
  experiments/output/input_checks.cpp experiments/output/csv.cpp fuzz/targets.cpp)
# The method-file target's sources: every .cpp of core/ and integrators/ but the references and
# the registration, plus the embedded built-in methods (generated as the build generates them).
mapfile -t lib_srcs < <(cd "$root" && find core integrators -name '*.cpp' \
  ! -path 'integrators/reference/*' ! -name register.cpp ! -path core/params.cpp | sort)
cmake -DOUT="$out/embedded_methods.cpp" -DDIR="$root/methods" -DPATTERN='*.toml' \
  -DFUNCTION=embedded_method_files -P "$root/cmake/embed_files.cmake"
# Compiles each source once (two at a time); an object newer than its source is kept.
compile() {
  local -n list=$1
  local -n objects=$2
  local extra=("${@:3}")
  local running=0
  for s in "${list[@]}"; do
    local src="$s"
    [[ "$s" = /* ]] || src="$root/$s"
    local o
    o="$out/$(echo "$s" | tr '/' '_' | sed 's/^_*//').o"
    if [ ! -f "$o" ] || [ "$src" -nt "$o" ]; then
      "$cxx" "${flags[@]}" "${extra[@]}" -c "$src" -o "$o" &
      running=$((running + 1))
      if [ "$running" -ge 2 ]; then
        wait -n
        running=$((running - 1))
      fi
    fi
    objects+=("$o")
  done
  wait
}
objs=()
compile srcs objs
lib_srcs+=("$out/embedded_methods.cpp" fuzz/method_file_target.cpp)
lib_objs=()
compile lib_srcs lib_objs -fopenmp
fail=0
targets=(params spec_file csv method_file)
for t in params spec_file csv; do
  "$cxx" "${flags[@]}" -fsanitize=fuzzer "$root/fuzz/fuzz_$t.cpp" "${objs[@]}" -ltomlplusplus \
    -o "$out/fuzz_$t"
done
"$cxx" "${flags[@]}" -fsanitize=fuzzer "$root/fuzz/fuzz_method_file.cpp" "${objs[@]}" \
  "${lib_objs[@]}" -ltomlplusplus -lklu -lumfpack -lamd -lcolamd -lbtf -lsuitesparseconfig \
  -fopenmp -o "$out/fuzz_method_file"
for t in "${targets[@]}"; do
  work="$out/corpus_$t"
  rm -rf "$work"
  mkdir -p "$work"
  dirs=("$root/fuzz/corpus/$t")
  [ -d "$root/fuzz/regressions/$t" ] && dirs+=("$root/fuzz/regressions/$t")
  find "${dirs[@]}" -type f ! -name '.*' -exec cp {} "$work/" \;
  log="$out/fuzz_$t.log"
  if (cd "$out" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      "./fuzz_$t" -max_total_time="$seconds" -print_final_stats=1 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$out/crash-$t-" "$work" >"$log" 2>&1); then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    rate=$(grep -o 'exec/s: [0-9]*' "$log" | tail -n 1 | grep -o '[0-9]*$' || echo "?")
    echo "fuzz $t: ${seconds} s, $runs inputs, $rate exec/s, no crash"
  else
    echo "fuzz $t: FAILED (inputs: $out/crash-$t-*)" >&2
    grep -E "ERROR|SUMMARY|runtime error|terminate|what\(\)" "$log" | head -n 20 >&2
    fail=1
  fi
done
exit "$fail"
