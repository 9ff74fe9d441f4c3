#!/usr/bin/env bash
# Configures (once) and builds the Release tree in build/ with warnings as errors.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DMPM_WERROR=ON >/dev/null
fi
cmake --build build -j "$(nproc)"
