#!/usr/bin/env bash
# Builds the libFuzzer target (clang, ASan + UBSan) in build-fuzz/ and fuzzes the configuration
# loader and expressions for FUZZ_SECONDS (default 60) from a seed corpus of examples/*.toml,
# tests/data/*.toml and fuzz/expressions.txt, copied into a temporary directory (nothing is
# written into the repository). Fails on any crash, hang, leak, sanitizer report or uncaught
# exception; the reproducer is kept in FUZZ_ARTIFACTS (default: the temporary directory, printed).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh clang libclang-rt-14-dev
seconds="${FUZZ_SECONDS:-60}"
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_COMPILER=clang++ -DMPM_FUZZ=ON -DMPM_BUILD_TESTS=OFF >/dev/null
fi
cmake --build build-fuzz --target fuzz_config -j "$(nproc)"

work=$(mktemp -d "${TMPDIR:-/tmp}/mpm-fuzz.XXXXXX")
corpus="$work/corpus"
artifacts="${FUZZ_ARTIFACTS:-$work/artifacts}"
mkdir -p "$corpus" "$artifacts"
cp examples/*.toml tests/data/*.toml "$corpus/"
i=0
while IFS= read -r line; do
  [ -n "$line" ] && printf '!%s' "$line" >"$corpus/expression_$((i += 1))"
done <fuzz/expressions.txt

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
status=0
build-fuzz/fuzz_config "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
  -max_len=8192 -print_final_stats=1 -artifact_prefix="$artifacts/" 2>"$work/fuzz.log" ||
  status=$?
tail -n 40 "$work/fuzz.log"
if [ "$status" -ne 0 ] || [ -n "$(ls -A "$artifacts")" ]; then
  echo "fuzz: FAILED (exit $status); log and reproducers kept in $work" >&2
  ls -l "$artifacts" >&2
  exit 1
fi
echo "fuzz: no findings in ${seconds} s"
rm -rf "$work"
