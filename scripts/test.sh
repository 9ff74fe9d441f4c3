#!/usr/bin/env bash
# Installs what is missing, builds (Release, warnings as errors) and runs the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
# ctest runs nproc test processes, each with nproc OpenMP threads: with the default (spinning)
# wait policy the idle threads of serial stages (the reconstruction mappings) take the cores
# from the working ones (a 2D MLS run on a loaded 2-core machine: 119 us per particle-step
# spinning, 7.6 us passive).
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
ctest --test-dir build --output-on-failure -j "$(nproc)"
