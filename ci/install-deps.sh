#!/usr/bin/env bash
# Install the Debian 12 packages qdemsph needs to build, test and verify.
# Idempotent: installs only what is missing; safe to run on every `make`.
# Usage: ci/install-deps.sh [--with-refs]   (--with-refs also installs yade)
set -euo pipefail

pkgs=(
  build-essential cmake pkg-config
  libeigen3-dev libyaml-cpp-dev libcli11-dev libfmt-dev libgtest-dev
  libhdf5-dev libgmsh-dev gmsh python3-gmsh
  libopenmpi-dev openmpi-bin
  python3-pytest python3-numpy python3-matplotlib python3-h5py python3-dolfinx
  yade
)

missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
