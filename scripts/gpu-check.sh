#!/usr/bin/env bash
# The GPU check in one call (issue 43), from the repository root of a fresh GPU machine that
# reaches no package registry: builds only what the check needs (the rll program and the GPU
# tests, with CUDA, against the Debian packages in .gpu-debs/ that scripts/gpu/fetch-debs.sh
# downloads on a Debian 12 machine), runs `ctest -L gpu`, then the frame times of bench/RESULTS.md's
# "GPU frame times": `rll render --device cuda` at 1920x1080 and 64 and 256 spp, ms per 1080p spp
# = (time at 256 spp - time at 64 spp) / 192 (the render's own time from --stats), median of
# --repeats, for cornell-boxes-room and arch-interior, power, tree and rll, depth 1 and 5; then
# the per-stage medians of `rll interactive --device cuda` (1080p frames of 1 spp). Writes the
# markdown tables to LOGS/gpu-frame-times.md and prints them; LOGS is $OUT, else BUILD/gpu-check.
# Each step's time is printed; aimed at under 8 minutes on 16 cores.
#   --cpu-tests        also build everything and run the CPU suite (ctest -L 'unit|cli|render|stat')
#   --repeats N        renders per spp count and case (default 3)
#   --system-packages  use this machine's libraries instead of .gpu-debs/
#   --build DIR        the build folder (default build-gpu)
#   --no-build         use the build folder as it is (configured and built before)
#   --dry-run          print the commands of the GPU steps instead of running them
#   --table-from FILE  only write the tables from a timings file (and the interactive --stats
#                      files beside it): no build, no GPU (to check this script)
# Exit status: 0 when everything built and passed and every timing ran.
set -uo pipefail
build=build-gpu
system_packages=0
cpu_tests=0
repeats=3
no_build=0
dry_run=0
table_from=""
usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --cpu-tests) cpu_tests=1 ;;
    --repeats)
      repeats="${2:-}"
      [[ "$repeats" =~ ^[1-9][0-9]?$ ]] || { echo "rll: gpu-check.sh: --repeats needs a whole number from 1 to 99 (got '${2:-}')" >&2; exit 2; }
      shift ;;
    --system-packages) system_packages=1 ;;
    --build) build="${2:?--build needs a folder}"; shift ;;
    --no-build) no_build=1 ;;
    --dry-run) dry_run=1 ;;
    --table-from) table_from="${2:?--table-from needs a timings file}"; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "rll: gpu-check.sh: unknown argument '$1' (see scripts/gpu-check.sh --help)" >&2; exit 2 ;;
  esac
  shift
done
[ -f CMakeLists.txt ] && [ -d src/rll ] || { echo "rll: gpu-check.sh runs from the repository root" >&2; exit 2; }
table_writer=scripts/gpu/frame_table.py

if [ -n "$table_from" ]; then
  [ -f "$table_from" ] || { echo "rll: gpu-check.sh: --table-from $table_from: no such file" >&2; exit 2; }
  shopt -s nullglob
  python3 "$table_writer" "$table_from" "$(dirname "$table_from")"/frames-*.json
  exit $?
fi

logs="${OUT:-$build/gpu-check}"
mkdir -p "$build" "$logs"
summary=()
failed=0
t_all=$SECONDS
note() { summary+=("$1"); echo "rll: $1"; }
# Runs a command, or prints it with --dry-run.
exec 3>&1  # (the terminal, for --dry-run inside redirections)
run() { if [ "$dry_run" = 1 ]; then echo "+ $*" >&3; else "$@"; fi; }

# --- build: only the program and the GPU tests (the CPU suite's programs with --cpu-tests) ---
if [ "$no_build" = 0 ]; then
  nvcc=$(command -v nvcc || true)
  [ -n "$nvcc" ] || { [ -x /usr/local/cuda/bin/nvcc ] && nvcc=/usr/local/cuda/bin/nvcc; }
  if [ -z "$nvcc" ]; then
    echo "rll: nvcc not found (neither on PATH nor /usr/local/cuda/bin/nvcc): the GPU build needs the CUDA toolkit" >&2
    exit 1
  fi
  bench=OFF
  [ "$cpu_tests" = 1 ] && bench=ON
  cmake_args=(-S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DRLL_CUDA=ON
              -DCMAKE_CUDA_COMPILER="$nvcc" -DRLL_BENCH=$bench -DRLL_FIGURES=OFF)
  command -v ccache > /dev/null && cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
  if [ "$system_packages" = 0 ]; then
    debs=(.gpu-debs/*.deb)
    if [ ! -e "${debs[0]}" ]; then
      echo "rll: .gpu-debs/ is empty: run scripts/gpu/fetch-debs.sh on a Debian 12 machine and bring .gpu-debs/ along (or pass --system-packages)" >&2
      exit 1
    fi
    prefix="$(cd "$build" && pwd)/debs"
    rm -rf "$prefix" && mkdir -p "$prefix"
    for d in "${debs[@]}"; do dpkg -x "$d" "$prefix" || { echo "rll: dpkg -x $d failed" >&2; exit 1; }; done
    # Debian's packaging in a prefix (../shared/GPU.md): the bare -lstb link, no RPATH, and
    # zlib1g-dev's libz.so an absolute link into Debian's /lib (this machine's libz.so.1 instead).
    lib="$prefix/usr/lib/x86_64-linux-gnu"
    zlib=$(ls /usr/lib/x86_64-linux-gnu/libz.so.1 /lib/x86_64-linux-gnu/libz.so.1 2> /dev/null | head -1)
    cmake_args+=(-DCMAKE_PREFIX_PATH="$prefix/usr" -DZLIB_INCLUDE_DIR="$prefix/usr/include"
                 -DZLIB_LIBRARY="${zlib:?rll: no libz.so.1 on this machine}")
    note "unpacked ${#debs[@]} packages into $prefix"
  fi
  t=$SECONDS
  if ! run cmake "${cmake_args[@]}" > "$logs/configure.log" 2>&1; then
    tail -30 "$logs/configure.log"
    echo "rll: configure failed (log: $logs/configure.log)" >&2
    exit 1
  fi
  if [ "$dry_run" = 0 ] && ! grep -q "rll: CUDA backend on" "$logs/configure.log"; then
    echo "rll: configured without the CUDA backend (log: $logs/configure.log)" >&2
    exit 1
  fi
  targets=(--target rll_cli rll_gpu_tests)
  [ "$cpu_tests" = 1 ] && targets=()
  if ! run cmake --build "$build" -j "$(nproc)" "${targets[@]}" > "$logs/build.log" 2>&1; then
    grep -B2 -A12 "FAILED\|error" "$logs/build.log" | head -60
    echo "rll: build failed (log: $logs/build.log)" >&2
    exit 1
  fi
  note "configured and built in $((SECONDS - t)) s with $(nproc) jobs ($nvcc)"
fi
# The libraries of the prefix, for every run (Debian's have no RPATH).
if [ -d "$build/debs/usr/lib/x86_64-linux-gnu" ]; then
  lib="$(cd "$build/debs/usr/lib/x86_64-linux-gnu" && pwd)"
  export LIBRARY_PATH="$lib${LIBRARY_PATH:+:$LIBRARY_PATH}"
  export LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
fi
rll="$build/rll"
[ "$dry_run" = 1 ] || [ -x "$rll" ] || { echo "rll: $rll was not built" >&2; exit 1; }
run "$rll" devices > "$logs/devices.log" 2>&1
[ "$dry_run" = 1 ] || head -3 "$logs/devices.log"

# --- tests: the GPU's (and the CPU's with --cpu-tests) ---
run_ctest() {
  local name=$1; shift
  local t=$SECONDS
  if [ "$dry_run" = 1 ]; then echo "+ (cd $build && ctest --output-on-failure -j $(nproc) $*)"; return; fi
  (cd "$build" && ctest --output-on-failure -j "$(nproc)" "$@") > "$logs/$name.log" 2>&1
  local rc=$?
  local line skipped
  line=$(grep -E "tests passed|tests failed" "$logs/$name.log" | tail -1)
  skipped=$(grep -c "\*\*\*Skipped\|Not Run" "$logs/$name.log")
  note "$name: ${line:-no tests ran}, $skipped skipped, $((SECONDS - t)) s (log: $logs/$name.log)"
  [ $rc -eq 0 ] || { failed=1; grep -E "\(Failed\)|\(SEGFAULT\)|\(Timeout\)|\(Subprocess" "$logs/$name.log" | head -20; }
}
run_ctest gpu-tests -L gpu
[ "$cpu_tests" = 1 ] && run_ctest cpu-tests -L 'unit|cli|render|stat'
if [ "$dry_run" = 0 ] && grep -q "^no GPU" "$logs/devices.log"; then
  note "no usable GPU here ($(grep '^no GPU' "$logs/devices.log" | head -1)): no frame times"
  echo
  echo "== rll GPU check: summary ($((SECONDS - t_all)) s in all)"
  printf '%s\n' "${summary[@]}"
  exit 1
fi

# --- frame times: render at 64 and 256 spp, --repeats times each, interleaved ---
timings="$logs/timings.tsv"
: > "$timings"
t=$SECONDS
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for rep in $(seq 1 "$repeats"); do
  for scene in cornell-boxes-room arch-interior; do
    for depth in 1 5; do
      for sampler in power tree rll; do
        for spp in 64 256; do
          name="render-$scene-$sampler-d$depth-${spp}spp-$rep"
          stats="$logs/$name.json"
          if run "$rll" render "builtin:$scene" --device cuda --sampler "$sampler" \
              --max-depth "$depth" --res 1920x1080 --spp "$spp" --quiet \
              -o "$scratch/image.exr" --stats "$stats" > "$logs/$name.log" 2>&1; then
            [ "$dry_run" = 1 ] && continue
            seconds=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"])' "$stats")
            printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$scene" "$sampler" "$depth" "$spp" "$rep" \
              "$seconds" "$stats" >> "$timings"
          else
            failed=1
            note "$name: FAILED (log: $logs/$name.log)"
          fi
        done
      done
    done
  done
done
note "frame times: $(wc -l < "$timings") renders in $((SECONDS - t)) s"

# --- the per-stage breakdown: 1080p frames of 1 spp, CUDA events per stage ---
t=$SECONDS
for scene in cornell-boxes-room arch-interior; do
  for depth in 1 5; do
    for sampler in power tree rll; do
      name="frames-$scene-$sampler-d$depth"
      if ! run "$rll" interactive "builtin:$scene" --device cuda --sampler "$sampler" \
          --max-depth "$depth" --frames 12 --warmup 4 --quiet --stats "$logs/$name.json" \
          > "$logs/$name.log" 2>&1; then
        failed=1
        note "$name: FAILED (log: $logs/$name.log)"
      fi
    done
  done
done
note "per-stage frames in $((SECONDS - t)) s"

if [ "$dry_run" = 0 ]; then
  shopt -s nullglob
  {
    echo "## GPU frame times"
    echo
    echo "$(head -1 "$logs/devices.log"); commit $(git rev-parse --short HEAD 2> /dev/null || echo unknown);" \
      "$(date -u +%Y-%m-%d); scripts/gpu-check.sh --repeats $repeats (render --device cuda --res 1920x1080" \
      "--spp 64 and 256, median of $repeats)"
    echo
    python3 "$table_writer" "$timings" "$logs"/frames-*.json
  } > "$logs/gpu-frame-times.md" || failed=1
  echo
  cat "$logs/gpu-frame-times.md"
fi

echo
echo "== rll GPU check: summary ($((SECONDS - t_all)) s in all)"
printf '%s\n' "${summary[@]}"
[ $failed -eq 0 ] && echo "all passed" || echo "SOMETHING FAILED: see the logs above"
exit $failed
