#!/usr/bin/env bash
# Same results before and after a change: runs `stiffbench report` (full, or --quick) and every
# sweep spec of suites/*.toml with two binaries and compares every CSV column but the
# wall times (scripts/compare_csv.py); then checks that `stiffbench run` on each section spec of
# the report (suites/report/*.toml) gives the rows of that section (NEW binary only).
#
#   scripts/compare-results.sh OLD_BIN NEW_BIN WORK_DIR [--quick]
#
# OLD_BIN is typically the binary of the commit before the change, e.g.
#   git worktree add /tmp/before HEAD~1 && scripts/build.sh /tmp/before/build   (in /tmp/before)
# Folders under WORK_DIR that already hold a finished report are reused (delete them to rerun).
# The full report takes about 15 minutes per binary on 2 cores; --quick about 2.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
old="$1" new="$2" work="$3" quick="${4:-}"
mkdir -p "$work"
status=0
report() {  # BIN DIR
  if [ ! -f "$2/REPORT.md" ]; then
    "$1" report $quick --force --out "$2" >/dev/null 2>"$2.log" || { tail "$2.log"; exit 1; }
  fi
}
echo "== report $quick: $old against $new"
report "$old" "$work/old/report"
report "$new" "$work/new/report"
python3 "$root/scripts/compare_csv.py" "$work/old/report" "$work/new/report" || status=1

echo "== sweep specs (stiffbench run)"
for spec in "$root"/suites/*.toml; do
  name="$(basename "$spec" .toml)"
  for side in old new; do
    bin="$old"; [ "$side" = new ] && bin="$new"
    rm -rf "$work/$side/specs/$name"
    "$bin" run "$spec" --out "$work/$side/specs/$name" >/dev/null 2>&1 || true
  done
  python3 "$root/scripts/compare_csv.py" "$work/old/specs/$name" "$work/new/specs/$name" || status=1
done

echo "== each report section spec through 'stiffbench run' (new binary) against its section"
for spec in "$root"/suites/report/*.toml; do
  name="$(basename "$spec" .toml)"; name="${name#[0-9][0-9]_}"
  [ -d "$work/new/report/$name" ] || { echo "skip $name (not in this report)"; continue; }
  sets=()
  if [ -n "$quick" ]; then
    # The [quick] settings of the section, as --set overrides (report --quick applies them).
    while IFS= read -r line; do sets+=(--set "$line"); done < <(
      awk '/^\[quick\]/{q=1;next} /^\[/{q=0} q && /=/ && !/^(title|note|skip)/ {
             sub(/ *#.*/, ""); gsub(/ = /, "="); print }' "$spec")
  fi
  rm -rf "$work/new/run/$name"
  "$new" run "$spec" "${sets[@]}" --out "$work/new/run/$name" >/dev/null 2>&1 || true
  csv="$(ls "$work/new/run/$name"/*.csv | head -1)"
  study="$work/new/report/$name/$(basename "$csv")"
  [ "$(basename "$csv")" = energy.csv ] && study="$work/new/report/$name/energy_summary.csv"
  [ "$(basename "$csv")" = region.csv ] && study="$work/new/report/$name/region_limits.csv"
  python3 "$root/scripts/compare_csv.py" --run "$csv" "$study" || status=1
done
exit $status
