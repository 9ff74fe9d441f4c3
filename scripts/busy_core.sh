#!/usr/bin/env bash
# A run on a machine with one core kept busy by another program (issue 23): the wall time of
# `mpm run` with its defaults next to the same run on one thread with the machine idle, and,
# for comparison, OpenMP's spinning wait policy with one thread per core. Prints the ratios.
#
# Usage: bash scripts/busy_core.sh [build/mpm]   (from the repository root)
set -euo pipefail
MPM=${1:-build/mpm}
[[ -x $MPM ]] || { echo "busy_core.sh: $MPM not found: build first (bash scripts/build.sh)" >&2; exit 2; }
work=$(mktemp -d)
busy_pid=
cleanup() { [[ -n $busy_pid ]] && kill "$busy_pid" 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT
cores=$(nproc)

time_run() {  # label, env assignments..., -- , mpm arguments...
  local label=$1; shift
  local envs=()
  while [[ $1 != -- ]]; do envs+=("$1"); shift; done
  shift
  local t0 t1
  t0=$(date +%s.%N)
  env -u OMP_WAIT_POLICY -u OMP_NUM_THREADS "${envs[@]}" "$MPM" run "$@" -q --overwrite \
    --out "$work/run" --set output.vtk=false --set output.csv=false > /dev/null
  t1=$(date +%s.%N)
  python3 -c "print(f'{$t1 - $t0:.3f}')"
}

for case in small large; do
  if [[ $case == small ]]; then   # the issue's example: 2304 particles, 2000 steps
    args=(examples/plate_mms_2d.toml --set grid.cells=16 --set mms.amplitude=0.05
          --set time.end=0.02 --set method.basis=linear)
  else                            # 16384 particles (two threads by default), 200 steps
    args=(examples/plate_mms_2d.toml --set grid.cells=32 --set particles.per_cell=4
          --set mms.amplitude=0.05 --set time.end=0.002 --set method.basis=linear)
  fi
  idle1=$(time_run idle1 OMP_NUM_THREADS=1 -- "${args[@]}")
  idle=$(time_run idle -- "${args[@]}")
  bash -c 'while :; do :; done' &
  busy_pid=$!
  busy=$(time_run busy -- "${args[@]}")
  spin=$(time_run spin OMP_WAIT_POLICY=active OMP_NUM_THREADS="$cores" -- "${args[@]}")
  kill "$busy_pid"; wait "$busy_pid" 2>/dev/null || true; busy_pid=
  python3 - "$case" "$idle1" "$idle" "$busy" "$spin" <<'PY'
import sys
case, idle1, idle, busy, spin = sys.argv[1], *map(float, sys.argv[2:])
print(f"{case}: idle, 1 thread {idle1:.2f} s; idle, defaults {idle:.2f} s; one core busy, "
      f"defaults {busy:.2f} s ({busy / idle1:.2f}x the idle 1-thread run); one core busy, "
      f"spinning with one thread per core {spin:.2f} s ({spin / idle1:.2f}x)")
PY
done
