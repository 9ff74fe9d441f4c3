#!/usr/bin/env bash
# mpm's one-thread 3D step against the 3D yardstick (issue 20, item 4): builds
# scripts/refkernel3d.cpp with the yardstick's flags (g++ -O3 -march=native -DNDEBUG), then per
# round runs, one after the other, the yardstick (CELLS^3 cells, 8 per cell) and
# `mpm bench --dim 3 --problem refkernel` on the same particles (quadratic B-splines, MUSL, one
# thread); prints both figures [ns per particle-step] and their ratio mpm / yardstick per round,
# then the median ratio over the rounds.
#
# Usage: scripts/refkernel3d.sh MPM ROUNDS [CELLS STEPS]   (default 32 cells per side, 10 steps)
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,9p' "$0" >&2
  exit 2
fi
mpm=$1 rounds=$2 cells=${3:-32} steps=${4:-10}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
g++ -O3 -march=native -DNDEBUG "$here/refkernel3d.cpp" -o "$tmp/refkernel3d"
export OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1
# 2 particles per cell and direction in both: the yardstick takes the count per cell (8), mpm
# the count per direction (--per-cell 2) and rounds cbrt(particles) / 2 to the cells per side.
particles=$((cells * cells * cells * 8))
ratios=()
for ((r = 1; r <= rounds; ++r)); do
  yout=$("$tmp/refkernel3d" "$cells" 8 "$steps")
  y=$(sed -n 's/.*ns_per_particle_step \([0-9.]*\).*/\1/p' <<<"$yout")
  [ "$r" -eq 1 ] && echo "yardstick's sums (compare between builds): $(sed -n 2p <<<"$yout")"
  if ! mout=$("$mpm" bench --dim 3 --problem refkernel --particles "$particles" --per-cell 2 \
    --basis bspline --degree 2 --scheme musl --steps "$steps" --repeats 1 --threads 1 2>&1); then
    echo "round $r: mpm bench failed:" >&2
    echo "$mout" >&2
    exit 1
  fi
  m=$(sed -n 's/^ *\([0-9.]*\) ns per particle-step.*/\1/p' <<<"$mout" | head -1)
  mp=$(sed -n 's/.*: \([0-9]*\) particles,.*/\1/p' <<<"$mout" | head -1)
  if [ -z "$y" ] || [ -z "$m" ] || [ "$mp" != "$particles" ]; then
    echo "round $r: could not read both figures on $particles particles; mpm printed:" >&2
    echo "$mout" >&2
    exit 1
  fi
  # mpm names the 2D problem in its header; a 3D header without "refkernel" means the binary
  # ran another problem (before --dim 3 --problem refkernel existed it ran the cube, with its
  # body force and rollers): the ratio then compares different problems.
  if [ "$r" -eq 1 ] && ! grep -q refkernel <<<"$(head -1 <<<"$mout")"; then
    echo "warning: mpm's header does not name the refkernel problem: $(head -1 <<<"$mout")" >&2
  fi
  q=$(awk -v a="$m" -v b="$y" 'BEGIN{printf "%.3f", a/b}')
  ratios+=("$q")
  echo "round $r: yardstick $y ns, mpm $m ns per particle-step ($particles particles); mpm / yardstick $q"
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR]=$1} END{print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
echo "median ratio mpm / yardstick over $rounds rounds: $(median "${ratios[@]}")"
