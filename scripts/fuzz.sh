#!/usr/bin/env bash
# Runs each fuzzer (the PLY, glTF, pbrt, JSON and OBJ+MTL parsers, the gzip inflater, the EXR
# reader, the image decoder) for a bounded time (make fuzz), each input held to 1 GiB of memory
# and 10 seconds.
# Usage: fuzz.sh BUILD SECONDS
set -euo pipefail
build=${1:-build-fuzz}
seconds=${2:-60}
root=$(cd "$(dirname "$0")/.." && pwd)
corpus=$build/corpus
crashes=$build/crashes
logs=$build/logs
rm -rf "$corpus/seeds"
mkdir -p "$crashes" "$logs"
"$build/fuzz/rll_fuzz_seeds" "$corpus/seeds"
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
status=0
for format in ply gltf pbrt json obj gzip exr image; do
  fuzzer=$build/fuzz/rll_fuzz_$format
  regressions=$root/tests/fuzz/$format
  mkdir -p "$corpus/$format"
  echo "== $format: regression inputs"
  if compgen -G "$regressions/*" > /dev/null; then
    "$fuzzer" -runs=0 -rss_limit_mb=1024 -timeout=10 "$regressions" || status=1
  fi
  echo "== $format: fuzzing for ${seconds}s (whole output in $logs/$format.log)"
  # The working corpus grows across runs; seeds and regression inputs are read-only extras.
  if ! "$fuzzer" "$corpus/$format" "$corpus/seeds/$format" "$regressions" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=1024 -max_len=65536 \
    -artifact_prefix="$crashes/$format-" -print_final_stats=1 > "$logs/$format.log" 2>&1; then
    status=1
    tail -n 40 "$logs/$format.log"
  fi
  # The final figures: runs, coverage, corpus (files/bytes), exec/s, peak RSS.
  grep -E '^#[0-9]+[[:space:]]+DONE|^stat::' "$logs/$format.log" || true
done
if [ "$status" -ne 0 ]; then
  echo "fuzz: a fuzzer found a crash; inputs are in $crashes (add them to tests/fuzz/<format>/)"
fi
exit $status
