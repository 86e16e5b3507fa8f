#!/usr/bin/env bash
# Determinism, on a built tree:
#  1. the same command twice gives byte-identical CSVs apart from the timing columns (wall_s,
#     wall_s_*, and repeats, whose count follows the measured times): a convergence study, a
#     work-precision study and a spec sweep;
#  2. 1 and 2 OpenMP threads give byte-identical trajectories for every registered model (its
#     defaults; parallel_threshold=1 where the model has one, so its parallel right-hand side
#     runs even at the small default size): 10 rk4 steps of h = 1e-4 written at full precision.
# Usage: scripts/check-determinism.sh [BUILD_DIR]   Prints one line per check; exit 1 on a
# difference.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
bin="$build/stiffbench"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail=0
checks=0

# CSV without the timing columns: wall_s, wall_s_*, repeats (any position).
strip_wall() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "wall_s" || $i ~ /^wall_s_/ || $i == "repeats") skip[i] = 1 }
           { out = ""; for (i = 1; i <= NF; i++) if (!skip[i]) out = out (out == "" ? "" : ",") $i;
             print out }' "$1"
}

same_twice() {
  local name="$1" csv="$2"
  shift 2
  for k in 1 2; do
    "$@" --out "$work/$name-$k" >/dev/null 2>"$work/$name-$k.log" || {
      echo "determinism: $name run $k failed"; cat "$work/$name-$k.log"; fail=1; return; }
  done
  checks=$((checks + 1))
  if cmp -s <(strip_wall "$work/$name-1/$csv") <(strip_wall "$work/$name-2/$csv"); then
    echo "determinism: $name twice: $csv identical apart from the timing columns ($(wc -l <"$work/$name-1/$csv") lines)"
  else
    echo "determinism: $name twice: $csv DIFFERS"
    diff <(strip_wall "$work/$name-1/$csv") <(strip_wall "$work/$name-2/$csv") | head -n 10
    fail=1
  fi
}

same_twice convergence convergence.csv "$bin" convergence --model kepler --param e=0.5 \
  --integrators rk4,velocity_verlet,sdirk2 --t-end 2 --h 0.05 --levels 3 --reference cvode_bdf
same_twice work-precision work_precision.csv "$bin" work-precision --model van_der_pol \
  --integrators rk4,cvode_bdf --t-end 1 --levels 3 --tol-levels 3
same_twice sweep convergence.csv "$bin" run "$root/suites/sweep_spring_chain.toml"

# 1 and 2 threads, every model.
models=$("$bin" list models | awk -F'|' 'NR > 2 { gsub(/ /, "", $2); print $2 }')
n=0
for m in $models; do
  params=()
  if "$bin" describe "$m" | grep -q '^| parallel_threshold '; then params=(--param parallel_threshold=1); fi
  for t in 1 2; do
    if ! OMP_NUM_THREADS=$t "$bin" solve --model "$m" --integrator rk4 --h 1e-4 --t-end 1e-3 \
        --outputs 10 "${params[@]}" --out "$work/$m-$t.csv" >/dev/null 2>"$work/$m-$t.log"; then
      echo "determinism: $m with $t thread(s) failed"; cat "$work/$m-$t.log"; fail=1; continue 2
    fi
  done
  checks=$((checks + 1))
  n=$((n + 1))
  if ! cmp -s "$work/$m-1.csv" "$work/$m-2.csv"; then
    echo "determinism: $m: 1 and 2 threads DIFFER"
    fail=1
  fi
done
echo "determinism: 1 and 2 threads: $n models compared"
if [ "$fail" = 0 ]; then echo "determinism: all $checks checks identical"; fi
exit "$fail"
