#!/usr/bin/env bash
# Checks a work_precision.csv: within each integrator, sorted by f_evals, the error must fall
# strictly as the work rises, and every row must have status ok. Rows flagged reference_floor
# (error within 10x of the reference's estimated error: it measures the reference as much as the
# method) are counted but not checked. Prints one line per integrator and exits 1 if any
# integrator violates it. Usage: check-work-precision.sh FILE.csv
set -euo pipefail
awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "flag") fc = i; next }
         { print $2, $5, $4, $10, (fc && $fc == "reference_floor") ? "floor" : "-" }' "$1" |
  sort -k1,1 -k2,2n | awk '
  { if ($1 != cur) { if (cur != "") report(); cur = $1; n = 0; bad = 0; nf = 0; prev = "" }
    n++; if ($5 == "floor") { nf++; next }
    if ($4 != "ok") bad++; else if (prev != "" && !($3 < prev)) bad++; prev = $3 }
  function report() { printf "%-14s %2d settings  %s%s\n", cur, n, bad ? "NOT monotone" : "error falls as work rises", nf ? " (" nf " at the reference floor, not checked)" : ""; if (bad) fail = 1 }
  END { report(); exit fail }'
