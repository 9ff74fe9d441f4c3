#!/usr/bin/env bash
# Installs what is missing, builds (Release) and runs the demo: a vibrating-bar convergence
# study (D 5.4.1, Table 3.1 set 2) over 5, 10, 20, 40 cells, writing demo-output/ (replacing
# the runs of an earlier demo there: --overwrite).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
build/mpm study examples/vibrating_bar_small.toml --refine grid.cells=5,10,20,40 --out demo-output \
  --overwrite
