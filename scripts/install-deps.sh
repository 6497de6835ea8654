#!/usr/bin/env bash
# Installs penumbra's build dependencies from Debian 12 packages (uses sudo when not run as root).
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libembree-dev libtbb-dev libopenexr-dev libpugixml-dev libtinyobjloader-dev libstb-dev
  libcli11-dev nlohmann-json3-dev zlib1g-dev libopenvdb-dev libblosc-dev libimath-dev libboost-iostreams-dev libtet1.5-dev libeigen3-dev libgtest-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-torch python3-pytest python3-setuptools python3-pip python3-pot
)
if [ "$(id -u)" -eq 0 ]; then sudo=""; else sudo="sudo"; fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
