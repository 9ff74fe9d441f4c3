#!/usr/bin/env bash
# Installs the Debian packages mpmlab needs, only those missing (idempotent, fast when nothing
# is missing). Run as root (or with sudo available). Extra packages can be given as arguments
# (scripts/fuzz.sh asks for clang and the compiler-rt libraries that hold libFuzzer).
set -euo pipefail
PACKAGES=(g++ cmake make ninja-build pkg-config libeigen3-dev libtomlplusplus-dev libcli11-dev
  libfmt-dev libmuparser-dev nlohmann-json3-dev libgtest-dev libgmsh-dev python3-matplotlib python3-meshio
  python3-sympy python3-vtk9 libopenmpi-dev openmpi-bin python3-dev python3-numpy pybind11-dev
  python3-pybind11 python3-pytest python3-scipy
  "$@")
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "installing: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
