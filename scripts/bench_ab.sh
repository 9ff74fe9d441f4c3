#!/usr/bin/env bash
# Same-run comparison of two mpm executables on `mpm bench`: the two alternate (A B A B ...) so
# that the load of a shared machine falls on both alike; prints each round's ns per
# particle-step and its ratio B / A, then the median of the round ratios (robust to a load
# change between rounds, which shifts both runs of a round alike) and the medians of A and B.
#
# Usage: scripts/bench_ab.sh A_MPM B_MPM ROUNDS [mpm bench options...]
#   e.g. scripts/bench_ab.sh old/build/mpm build/mpm 5 --dim 2 --basis bspline --degree 2 \
#        --threads 1 --particles 1000000
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,9p' "$0" >&2
  exit 2
fi
a=$1 b=$2 rounds=$3
shift 3
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
ta=() tb=() tr=()
for ((r = 1; r <= rounds; ++r)); do
  x=$("$a" bench "$@" 2>&1 | sed -n 's/^ *\([0-9.]*\) ns per particle-step.*/\1/p' | head -1)
  y=$("$b" bench "$@" 2>&1 | sed -n 's/^ *\([0-9.]*\) ns per particle-step.*/\1/p' | head -1)
  [ -n "$x" ] && [ -n "$y" ] || { echo "bench_ab: a run printed no figure" >&2; exit 1; }
  ta+=("$x") tb+=("$y")
  tr+=("$(awk -v x="$x" -v y="$y" 'BEGIN{printf "%.4f", y/x}')")
  echo "round $r: A $x ns, B $y ns (B/A ${tr[-1]})"
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END{print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
ma=$(median "${ta[@]}") mb=$(median "${tb[@]}")
echo "median of the round ratios B/A = $(median "${tr[@]}"); medians A $ma ns, B $mb ns per particle-step"
