#!/usr/bin/env bash
# Builds and runs the cost benchmarks (bench/, target stiffbench_bench; README,
# "Performance"). Usage:
#   scripts/bench.sh [--full] [--build DIR] [stiffbench_bench / Google Benchmark flags ...]
# Installs the Debian packages the benchmark needs (idempotent: apt is skipped when all are
# present), configures a Release build with -DSTIFFBENCH_BUILD_BENCH=ON (default folder
# build-bench), builds stiffbench_bench and runs it with --quick (under two minutes on a
# 2-core machine), or every size and thread count with --full (5 repetitions of each unless
# --benchmark_repetitions=N is given; the summary reports medians and a bootstrap 95% interval of
# each median). Further flags go to the program, e.g. --benchmark_filter='rhs/.*' or
# --benchmark_repetitions=3.
# PySPH's dam break beside the testbed's: scripts/bench_pysph.sh.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-bench"
mode="--quick"
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --full) mode="" ;;
    --quick) mode="--quick" ;;
    --build) build="$2"; shift ;;
    *) args+=("$1") ;;
  esac
  shift
done

packages=(
  build-essential cmake
  libeigen3-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  libbenchmark-dev libboost-dev libgsl-dev libsundials-dev
)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "bench: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DSTIFFBENCH_BUILD_BENCH=ON \
  -DSTIFFBENCH_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target stiffbench_bench

echo "bench: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
start=$(date +%s)
"$build/bench/stiffbench_bench" ${mode:+"$mode"} ${args[@]+"${args[@]}"}
echo "bench: stiffbench_bench ${mode:-(full)} took $(( $(date +%s) - start )) s"
