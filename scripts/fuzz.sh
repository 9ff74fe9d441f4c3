#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in build-fuzz/ and fuzzes
#  - the configuration loader and expressions for FUZZ_SECONDS (default 60), from a seed corpus
#    of examples/*.toml, tests/data/*.toml, fuzz/expressions.txt and two deeply nested keys
#    (issue 16: 40,000 levels overflowed toml++'s stack), inputs up to 128 KiB;
#  - the checkpoint loader for FUZZ_CHECKPOINT_SECONDS (default 30), from the payloads of
#    checkpoints that build/mpm writes for a few small runs (when it has been built; otherwise
#    from an empty corpus).
# The corpora live in a temporary directory (nothing is written into the repository). Fails on
# any crash, hang, leak, sanitizer report or uncaught exception; the reproducer is kept in
# FUZZ_ARTIFACTS (default: the temporary directory, printed).
# FUZZ_BUILD: the build tree of the targets (default build-fuzz/, configured here at -O2 -g).
# scripts/sanitize.sh with FUZZ_ALONGSIDE=1 (CI) builds them in its instrumented tree build-asan/
# (-O0, the same sanitizers) and runs this script with FUZZ_BUILD=build-asan: the five sources
# they compile cost about 170 s of CPU in a tree of their own at -O2 -g, about 40 s there.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh clang libclang-rt-14-dev
seconds="${FUZZ_SECONDS:-60}"
checkpoint_seconds="${FUZZ_CHECKPOINT_SECONDS:-30}"
build="${FUZZ_BUILD:-build-fuzz}"
if [ "$build" = build-fuzz ] && [ ! -f build-fuzz/CMakeCache.txt ]; then
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_COMPILER=clang++ -DMPM_FUZZ=ON -DMPM_BUILD_TESTS=OFF -DMPM_PYTHON=OFF >/dev/null
fi
cmake --build "$build" --target fuzz_config fuzz_checkpoint -j "$(nproc)"

work=$(mktemp -d "${TMPDIR:-/tmp}/mpm-fuzz.XXXXXX")
corpus="$work/corpus"
artifacts="${FUZZ_ARTIFACTS:-$work/artifacts}"
mkdir -p "$corpus" "$work/checkpoints" "$artifacts"
cp examples/*.toml tests/data/*.toml "$corpus/"
i=0
while IFS= read -r line; do
  [ -n "$line" ] && printf '!%s' "$line" >"$corpus/expression_$((i += 1))"
done <fuzz/expressions.txt
python3 -c 'print("a." * 40000 + "a = 1")' >"$corpus/nested_dotted_key.toml"
python3 -c 'print("[" + "a." * 40000 + "a]\nb = 1")' >"$corpus/nested_header.toml"

# Checkpoint payloads (the file less its 28-byte header; fuzz/fuzz_checkpoint.cpp puts one back)
# of small runs: 1D and 2D, a FEM reference, TLS and MLS totals, CPDI2 corners, the ULFEM solver,
# a distributed run's manifest and pieces.
if [ -x build/mpm ]; then
  n=0
  seed() {
    local config=$1
    shift
    local out="$work/run_$((n += 1))"
    if build/mpm run "$config" -q --out "$out" --set output.checkpoint_every=1 \
      --set output.vtk=false "$@" >/dev/null 2>&1; then
      tail -c +29 "$out/checkpoint.bin" >"$work/checkpoints/seed_$n"
    else
      echo "fuzz: no checkpoint seed from $config $*" >&2
    fi
    rm -rf "$out"
  }
  seed examples/vibrating_bar_small.toml --set time.end=5e-7 --set grid.cells=4
  seed examples/vibrating_bar_small.toml --set time.end=5e-7 --set grid.cells=4 \
    --set method.mapping=tls
  seed examples/vibrating_bar_small.toml --set time.end=5e-7 --set grid.cells=4 \
    --set method.mapping=mls
  seed examples/vibrating_bar_small.toml --set time.end=5e-7 --set grid.cells=4 \
    --set method.solver=ulfem
  seed examples/vibrating_bar_large.toml --set time.end=3e-4 --set grid.cells=4 \
    --set reference.dofs=5
  seed examples/plate_mms_2d.toml --set time.end=1e-4 --set grid.cells=2
  seed examples/plate_mms_2d.toml --set time.end=1e-4 --set grid.cells=2 \
    --set method.basis=cpdi2
  # A distributed run's manifest and pieces (the pieces' payloads after a 'P', which sends them to
  # the piece decoder), when Open MPI is there.
  out="$work/run_mpi"
  if command -v mpirun >/dev/null &&
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -n 2 --oversubscribe \
      build/mpm run examples/plate_mms_2d.toml -q --out "$out" --set output.checkpoint_every=1 \
      --set output.vtk=false --set time.end=1e-4 --set grid.cells=2 --set method.basis=cpdi2 \
      >/dev/null 2>&1; then
    tail -c +29 "$out/checkpoint.bin" >"$work/checkpoints/seed_manifest"
    for piece in "$out"/checkpoint_s*_p*.bin; do
      { printf P; tail -c +29 "$piece"; } >"$work/checkpoints/seed_$(basename "$piece" .bin)"
    done
  else
    echo "fuzz: no distributed checkpoint seed (mpirun missing or the run failed)" >&2
  fi
  rm -rf "$out"
fi

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
status=0
"$build/fuzz_config" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
  -max_len=131072 -print_final_stats=1 -artifact_prefix="$artifacts/" 2>"$work/fuzz.log" ||
  status=$?
tail -n 20 "$work/fuzz.log"
if [ "$status" -eq 0 ]; then
  seeds=$(ls "$work/checkpoints" | wc -l)
  "$build/fuzz_checkpoint" "$work/checkpoints" -max_total_time="$checkpoint_seconds" \
    -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" 2>"$work/fuzz_checkpoint.log" || status=$?
  echo "-- checkpoint loader ($seeds seed payloads)"
  tail -n 20 "$work/fuzz_checkpoint.log"
fi
if [ "$status" -ne 0 ] || [ -n "$(ls -A "$artifacts")" ]; then
  echo "fuzz: FAILED (exit $status); logs and reproducers kept in $work" >&2
  ls -l "$artifacts" >&2
  exit 1
fi
echo "fuzz: no findings in ${seconds} s (configuration) and ${checkpoint_seconds} s (checkpoints)"
rm -rf "$work"
