#!/usr/bin/env bash
# The main job: install dependencies, build, and run `stiffbench report` on the default suite.
# Usage: scripts/report.sh [OUT_DIR] [--quick] [--force]     (default OUT_DIR: results; running
# it again with the same suite replaces the results, the other suite needs --force)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-results}"
shift || true
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$root/build"
"$root/build/stiffbench" report --out "$out" "$@"
