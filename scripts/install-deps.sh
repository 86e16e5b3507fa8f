#!/usr/bin/env bash
# Installs the Debian packages stiffbench needs (docs/README.md, Set-up). Idempotent: apt is
# skipped when every package is already installed. Run as root on Debian 12.
set -euo pipefail

packages=(
  build-essential cmake git
  libeigen3-dev libsundials-dev libgsl-dev libboost-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox clang-format
  chromium
  clang libclang-rt-14-dev libomp-dev
  python3
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
