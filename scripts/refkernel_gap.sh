#!/usr/bin/env bash
# The one-thread gap between mpm's step and the yardstick, attributed by measurement (issue 23):
# builds ../shared/tools/refkernel.cpp and scripts/refkernel_gap.cpp with the yardstick's flags,
# then per round runs, one after the other, the yardstick, the gap kernel without and with each
# piece of mpm's extra work (see the header of refkernel_gap.cpp) and with all of them, and
# `mpm bench --problem refkernel` on the same particles; prints each figure and its ratio to
# the yardstick of its round, then the median ratio over the rounds.
#
# Usage: scripts/refkernel_gap.sh MPM ROUNDS [CELLS STEPS]   (default 333 cells per side, 10 steps)
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,9p' "$0" >&2
  exit 2
fi
mpm=$1 rounds=$2 cells=${3:-333} steps=${4:-10}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
g++ -O3 -march=native -DNDEBUG "$here/../../shared/tools/refkernel.cpp" -o "$tmp/refkernel"
g++ -O3 -march=native -DNDEBUG -std=c++20 "$here/refkernel_gap.cpp" -o "$tmp/gap"
export OMP_WAIT_POLICY=passive
particles=$((cells * cells * 9))
names=(yardstick "gap 0 (none)" "gap 1 (state)" "gap 2 (checks)" "gap 4 (body)" "gap 8 (cache)"
  "gap 16 (slices)" "gap 27 (all but body)" "gap 31 (all)" "mpm")
declare -A ratios
for ((r = 1; r <= rounds; ++r)); do
  figs=()
  figs+=("$("$tmp/refkernel" "$cells" 9 "$steps" | sed -n 's/.*ns_per_particle_step \([0-9.]*\).*/\1/p')")
  for m in 0 1 2 4 8 16 27 31; do
    figs+=("$("$tmp/gap" "$cells" 9 "$steps" "$m" | sed -n 's/.*ns_per_particle_step \([0-9.]*\).*/\1/p')")
  done
  figs+=("$("$mpm" bench --dim 2 --particles "$particles" --per-cell 3 --basis bspline --degree 2 \
    --scheme musl --steps "$steps" --repeats 1 --problem refkernel --threads 1 2>&1 |
    sed -n 's/^ *\([0-9.]*\) ns per particle-step.*/\1/p' | head -1)")
  line="round $r:"
  for i in "${!names[@]}"; do
    q=$(awk -v a="${figs[$i]}" -v b="${figs[0]}" 'BEGIN{printf "%.3f", a/b}')
    ratios[$i]="${ratios[$i]:-} $q"
    line+=" ${names[$i]} ${figs[$i]} ($q);"
  done
  echo "$line"
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END{print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
echo "median ratio to the yardstick over $rounds rounds:"
for i in "${!names[@]}"; do
  # shellcheck disable=SC2086
  echo "  ${names[$i]}: $(median ${ratios[$i]})"
done
