#!/usr/bin/env bash
# Installs pp5sim's build and test dependencies from Debian 12's packages.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config python3
  libsystemc-dev libglm-dev libfmt-dev catch2 nlohmann-json3-dev libcli11-dev libpng-dev libassimp-dev
  libbenchmark-dev gtkwave librsvg2-bin clang libclang-rt-dev
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
