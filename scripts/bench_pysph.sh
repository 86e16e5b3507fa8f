#!/usr/bin/env bash
# The 2D dam break in PySPH and in stiffbench at matched particle counts over the same simulated
# time: prints each one's cost per particle per right-hand-side
# evaluation and their ratio. Usage:
#   scripts/bench_pysph.sh [--t-end T] [--threads N] [--build DIR]
# Defaults: T = 0.1 s of simulated time, N = 2 OpenMP threads, build folder build-bench.
#
# PySPH: Debian's python3-pysph, installed here only (not by the main set-up; idempotent), its
# own example `python3 -m pysph.examples.dam_break_2d` with its default WCSPH scheme (PEC
# integrator: one acceleration evaluation per step) and --openmp, default dx = 0.03: 2,278 fluid
# + 1,660 boundary particles = 3,938, all of which PySPH's equations update (its WCSPH boundary
# particles carry a density equation). Its cost per RHS evaluation is (acceleration_eval +
# nnps.update) from PySPH's own profile (profile_info.csv) per call, divided by 3,938. A first
# short run compiles PySPH's generated code (~20 s) and is not timed.
# stiffbench: `stiffbench solve --model sph_dam_break_2d --param n=45` (4,050 fluid particles;
# boundary particles are fixed and not evaluated) with symplectic_euler at the model's suggested
# step; its cost per RHS evaluation is the run's wall_s / f_evals / 4,050 (the step's own update
# included).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-bench"
t_end="0.1"
threads="2"
while [ $# -gt 0 ]; do
  case "$1" in
    --t-end) t_end="$2"; shift ;;
    --threads) threads="$2"; shift ;;
    --build) build="$2"; shift ;;
    *) echo "bench_pysph: unknown argument $1" >&2; exit 2 ;;
  esac
  shift
done

if ! dpkg-query -W -f='${Status}' python3-pysph 2>/dev/null | grep -q "install ok installed"; then
  echo "bench_pysph: installing python3-pysph"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  if ! { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends \
      python3-pysph; }; then
    echo "bench_pysph: python3-pysph could not be installed here; no PySPH comparison" >&2
    exit 1
  fi
fi

jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DSTIFFBENCH_BUILD_BENCH=ON \
  -DSTIFFBENCH_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target stiffbench >/dev/null

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
echo "bench_pysph: $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)," \
  "$threads threads, simulated time $t_end s"

# PySPH: compile (untimed), then the measured run.
(cd "$work" && OMP_NUM_THREADS="$threads" /usr/bin/python3 -m pysph.examples.dam_break_2d \
  --openmp --max-steps 2 --disable-output -d "$work/warm" >"$work/warm.log" 2>&1) || {
  echo "bench_pysph: PySPH's dam_break_2d does not run here:" >&2
  tail -n 20 "$work/warm.log" >&2
  exit 1
}
(cd "$work" && OMP_NUM_THREADS="$threads" /usr/bin/python3 -m pysph.examples.dam_break_2d \
  --openmp --tf "$t_end" --disable-output -d "$work/pysph" >"$work/pysph.log" 2>&1)

# stiffbench at the matched count.
OMP_NUM_THREADS="$threads" "$build/stiffbench" solve --model sph_dam_break_2d \
  --param n=45 --integrator symplectic_euler --t-end "$t_end" >"$work/testbed.log" 2>&1

/usr/bin/python3 - "$work" <<'EOF'
import csv, re, sys
work = sys.argv[1]
log = open(f"{work}/pysph.log").read()
total = int(re.search(r"Total:\s*(\d+)", log).group(1))
fluid = int(re.search(r"fluid:\s*(\d+)", log).group(1))
run = float(re.search(r"Run took:\s*([0-9.eE+-]+)", log).group(1))
prof = {r["function"]: r for r in csv.DictReader(open(f"{work}/pysph/profile_info.csv"))}
calls = int(prof["acceleration_eval_0"]["calls"])
acc = float(prof["acceleration_eval_0"]["time"])
nnps = float(prof["nnps.update"]["time"]) if "nnps.update" in prof else 0.0
py_eval = (acc + nnps) / calls
py_us = py_eval / total * 1e6
tb = open(f"{work}/testbed.log").read()
stat = lambda k: re.search(rf"^\s*{k}\s+(\S+)", tb, re.M).group(1)
if stat("status") != "ok":
    sys.exit("bench_pysph: the stiffbench run did not end ok:\n" + tb[-2000:])
f_evals, wall = int(stat("f_evals")), float(stat("wall_s"))
tb_particles = 4050
tb_us = wall / f_evals / tb_particles * 1e6
print(f"PySPH dam_break_2d (WCSPH, PEC): {total} particles ({fluid} fluid), {calls} RHS "
      f"evaluations in {run:.2f} s of run time; RHS (acceleration_eval + nnps.update) "
      f"{py_eval * 1e3:.3g} ms = {py_us:.3g} us per particle per RHS evaluation "
      f"({py_eval / fluid * 1e6:.3g} us per fluid particle; whole step incl. integrator "
      f"stages {run / calls / total * 1e6:.3g} us per particle)")
print(f"stiffbench sph_dam_break_2d n=45 (symplectic_euler): {tb_particles} fluid particles, "
      f"{f_evals} RHS evaluations in {wall:.2f} s = {tb_us:.3g} us per particle per RHS "
      f"evaluation (step update included)")
print(f"ratio stiffbench / PySPH per particle per RHS evaluation: {tb_us / py_us:.3g} "
      f"(target: stiffbench <= 0.3 us)")
EOF
