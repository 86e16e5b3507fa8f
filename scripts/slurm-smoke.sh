#!/usr/bin/env bash
# Smoke test of `stiffbench run --slurm` on a real (single-node, localhost) Slurm:
#   scripts/slurm-smoke.sh [--local] [BUILD_DIR]      (BUILD_DIR default: build)
# As root: installs Debian's slurm-wlm and munge if missing, writes a minimal slurm.conf under
# a temporary directory (linuxproc process tracking, no cgroups, no accounting), starts munged
# (if not running), slurmctld and slurmd in the background, writes the job scripts of a 4-task
# array with `stiffbench run SPEC --slurm 4`, submits them with the generated submit.sh (array,
# then the merge job with --dependency=afterok), waits (timeout 150 s), and compares the merged
# CSV with an unsharded local run, ignoring the wall_s column. Stops what it started.
# --local: no Slurm; runs the 4 shards and the merge locally with the same comparison.
# Exit 0 when the CSVs match.
set -euo pipefail

local_only=0
if [[ "${1:-}" == "--local" ]]; then
  local_only=1
  shift
fi
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${1:-build}
[[ "$BUILD" = /* ]] || BUILD="$ROOT/$BUILD"
BIN="$BUILD/stiffbench"
SPEC="$ROOT/suites/sweep_spring_chain.toml"
N=4
[[ -x "$BIN" ]] || { echo "slurm-smoke: $BIN not found (build first)" >&2; exit 1; }

T=$(mktemp -d /tmp/stiffbench-slurm.XXXXXX)
started=()
cleanup() {
  local pids=()
  for pidfile in "${started[@]}"; do
    [[ -f "$pidfile" ]] && pids+=("$(cat "$pidfile")") && kill "${pids[-1]}" 2>/dev/null || true
  done
  # The daemons write their state while they shut down: wait for them (at most 10 s) before
  # removing their folders.
  for _ in $(seq 100); do
    local alive=0
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
    ((alive)) || break
    sleep 0.1
  done
  if [[ -z "${KEEP:-}" ]]; then rm -rf "$T" || true; else echo "slurm-smoke: kept $T"; fi
}
trap cleanup EXIT

# The CSV without its wall_s column (the only column that differs between runs).
strip_wall() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "wall_s") w = i }
           { s = ""; for (i = 1; i <= NF; i++) if (i != w) s = s $i ","; print s }' "$1"
}

start=$(date +%s)
echo "slurm-smoke: unsharded reference run"
"$BIN" run "$SPEC" --out "$T/local" > /dev/null

if [[ $local_only == 1 ]]; then
  for ((i = 0; i < N; i++)); do
    "$BIN" run "$SPEC" --shard "$i/$N" --out "$T/out/shard-$i" > /dev/null
  done
  "$BIN" merge --out "$T/out" $(for ((i = 0; i < N; i++)); do echo "$T/out/shard-$i"; done)
else
  if [[ $(id -u) != 0 ]]; then
    echo "slurm-smoke: run as root (installs packages, starts daemons), or use --local" >&2
    exit 1
  fi
  if ! command -v slurmctld > /dev/null || ! command -v munged > /dev/null; then
    echo "slurm-smoke: installing slurm-wlm and munge"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends slurm-wlm \
      munge > "$T/apt.log"
  fi
  # munge: a key if missing, the daemon if not running.
  if [[ ! -s /etc/munge/munge.key ]]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 2> /dev/null
  fi
  chown munge:munge /etc/munge/munge.key 2> /dev/null || true
  chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/lib/munge /var/log/munge
  chown munge:munge /run/munge /var/lib/munge /var/log/munge 2> /dev/null || true
  if ! munge -n > /dev/null 2>&1; then
    # (the pid file where the munge user may write it)
    runuser -u munge -- munged --pid-file=/run/munge/stiffbench-smoke-munged.pid
    started+=(/run/munge/stiffbench-smoke-munged.pid)
    for _ in $(seq 50); do munge -n > /dev/null 2>&1 && break; sleep 0.1; done
  fi

  host=$(hostname -s)
  mkdir -p "$T/state" "$T/spool"
  export SLURM_CONF="$T/slurm.conf"
  cat > "$SLURM_CONF" << EOF
ClusterName=smoke
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=smoke Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  slurmctld -f "$SLURM_CONF"
  started+=("$T/slurmctld.pid")
  slurmd -f "$SLURM_CONF"
  started+=("$T/slurmd.pid")
  for _ in $(seq 100); do
    sinfo -h -o %t 2> /dev/null | grep -q idle && break
    sleep 0.2
  done
  sinfo -h -o %t | grep -q idle || {
    echo "slurm-smoke: the node did not come up" >&2
    tail -5 "$T/slurmctld.log" "$T/slurmd.log" >&2
    exit 1
  }
  echo "slurm-smoke: Slurm up after $(($(date +%s) - start)) s"

  "$BIN" run "$SPEC" --slurm "$N" --partition smoke --time 00:05:00 --out "$T/out"
  ids=$(bash "$T/out/slurm/submit.sh")
  echo "slurm-smoke: $ids"
  merge_id=$(sed -n 's/.*merge job \([0-9]*\).*/\1/p' <<< "$ids")
  for _ in $(seq 750); do
    [[ -z "$(squeue -h 2> /dev/null)" ]] && break
    sleep 0.2
  done
  if [[ -n "$(squeue -h)" ]]; then
    echo "slurm-smoke: jobs still queued after 150 s:" >&2
    squeue >&2
    exit 1
  fi
  [[ -f "$T/out/slurm/merge.log" ]] || {
    echo "slurm-smoke: merge job $merge_id did not run" >&2
    cat "$T"/out/slurm/*.log >&2 2> /dev/null || true
    exit 1
  }
  cat "$T/out/slurm/merge.log"
fi

if diff <(strip_wall "$T/local/convergence.csv") <(strip_wall "$T/out/convergence.csv") \
  > "$T/diff.txt"; then
  echo "slurm-smoke: merged CSV of $N shards matches the unsharded run" \
    "($(($(wc -l < "$T/out/convergence.csv") - 1)) rows, $(($(date +%s) - start)) s)"
else
  echo "slurm-smoke: merged CSV differs from the unsharded run:" >&2
  head -20 "$T/diff.txt" >&2
  exit 1
fi
