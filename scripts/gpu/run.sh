#!/usr/bin/env bash
# Run on the GPU machine from the repository root: builds rll with CUDA against the libraries in
# .gpu-debs/ (scripts/gpu/fetch-debs.sh fetches them on a Debian 12 machine; they are unpacked
# into a prefix under the build folder, never into /), runs the GPU tests (ctest -L gpu), then
# the unit, cli, render and stat tests (not slurm; those needing Chromium skip themselves), then
# every GPU benchmark program that was built and 1080p frames of the GPU wavefront renderer
# (rll interactive --device cuda). Logs go to $OUT (else <build>/gpu-logs); a short
# summary comes last. Exit status: 0 when everything built and passed.
#   --system-packages  use the libraries installed on this machine instead of .gpu-debs/
#   --build DIR        the build folder (default build-gpu)
set -uo pipefail
build=build-gpu
system_packages=0
while [ $# -gt 0 ]; do
  case "$1" in
    --system-packages) system_packages=1 ;;
    --build) build="${2:?--build needs a folder}"; shift ;;
    -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "rll: run.sh: unknown argument '$1' (see scripts/gpu/run.sh --help)" >&2; exit 2 ;;
  esac
  shift
done
[ -f CMakeLists.txt ] && [ -d src/rll ] || { echo "rll: run.sh runs from the repository root" >&2; exit 2; }

nvcc=$(command -v nvcc || true)
[ -n "$nvcc" ] || { [ -x /usr/local/cuda/bin/nvcc ] && nvcc=/usr/local/cuda/bin/nvcc; }
if [ -z "$nvcc" ]; then
  echo "rll: nvcc not found (neither on PATH nor /usr/local/cuda/bin/nvcc): the GPU build needs the CUDA toolkit" >&2
  exit 1
fi

logs="${OUT:-$build/gpu-logs}"
mkdir -p "$build" "$logs"
summary=()
failed=0
note() { summary+=("$1"); echo "rll: $1"; }

cmake_args=(-S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DRLL_CUDA=ON
            -DCMAKE_CUDA_COMPILER="$nvcc")
command -v ccache > /dev/null && cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# The GPU machine has no librsvg or pango (and reaches no registry to fetch them): build without
# compare's PNG figures there (report.html still draws every figure).
pkg-config --exists librsvg-2.0 pangocairo 2> /dev/null || cmake_args+=(-DRLL_FIGURES=OFF)
if [ "$system_packages" -eq 0 ]; then
  debs=(.gpu-debs/*.deb)
  if [ ! -e "${debs[0]}" ]; then
    echo "rll: .gpu-debs/ is empty: run scripts/gpu/fetch-debs.sh on a Debian 12 machine and bring .gpu-debs/ along (or pass --system-packages)" >&2
    exit 1
  fi
  prefix="$(cd "$build" && pwd)/debs"
  rm -rf "$prefix" && mkdir -p "$prefix"
  for d in "${debs[@]}"; do dpkg -x "$d" "$prefix" || { echo "rll: dpkg -x $d failed" >&2; exit 1; }; done
  lib="$prefix/usr/lib/x86_64-linux-gnu"
  # Debian's packaging in a prefix: the bare -lstb link, no RPATH, and zlib1g-dev's libz.so being
  # an absolute link into Debian's /lib (the machine's own libz.so.1 is used instead).
  export LIBRARY_PATH="$lib${LIBRARY_PATH:+:$LIBRARY_PATH}"
  export LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  zlib=$(ls /usr/lib/x86_64-linux-gnu/libz.so.1 /lib/x86_64-linux-gnu/libz.so.1 2> /dev/null | head -1)
  cmake_args+=(-DCMAKE_PREFIX_PATH="$prefix/usr" -DZLIB_INCLUDE_DIR="$prefix/usr/include"
               -DZLIB_LIBRARY="${zlib:?rll: no libz.so.1 on this machine}")
  note "unpacked ${#debs[@]} packages into $prefix"
fi

start=$SECONDS
if ! cmake "${cmake_args[@]}" > "$logs/configure.log" 2>&1; then
  tail -30 "$logs/configure.log"
  echo "rll: configure failed (log: $logs/configure.log)" >&2
  exit 1
fi
if ! grep -q "rll: CUDA backend on" "$logs/configure.log"; then
  echo "rll: configured without the CUDA backend (log: $logs/configure.log)" >&2
  exit 1
fi
if ! cmake --build "$build" -j "$(nproc)" > "$logs/build.log" 2>&1; then
  grep -B2 -A12 "FAILED\|error" "$logs/build.log" | head -60
  echo "rll: build failed (log: $logs/build.log)" >&2
  exit 1
fi
note "configured and built in $((SECONDS - start)) s with $(nproc) jobs ($nvcc)"
"$build/rll" devices > "$logs/devices.log" 2>&1
cat "$logs/devices.log"

# The outcome of one ctest run, from its log: "N passed, M failed, K skipped".
run_ctest() {
  local name=$1; shift
  (cd "$build" && ctest --output-on-failure -j "$(nproc)" "$@") > "$logs/$name.log" 2>&1
  local rc=$?
  local line
  line=$(grep -E "tests passed|tests failed" "$logs/$name.log" | tail -1)
  local skipped
  skipped=$(grep -c "\*\*\*Skipped\|Not Run" "$logs/$name.log")
  note "$name: ${line:-no tests ran}, $skipped skipped (log: $logs/$name.log)"
  [ $rc -eq 0 ] || { failed=1; grep -E "\(Failed\)|\(SEGFAULT\)|\(Timeout\)|\(Subprocess" "$logs/$name.log" | head -20; }
}
run_ctest gpu-tests -L gpu
run_ctest cpu-tests -L 'unit|cli|render|stat'

shopt -s nullglob
benches=("$build"/bench/rll_gpu_*)
for b in "${benches[@]}"; do
  [ -x "$b" ] || continue
  name=$(basename "$b")
  if "$b" > "$logs/$name.log" 2>&1; then
    note "$name: ok (log: $logs/$name.log)"
  else
    failed=1
    note "$name: FAILED, exit $? (log: $logs/$name.log)"
  fi
done
[ ${#benches[@]} -gt 0 ] || note "no GPU benchmark programs built yet (bench/rll_gpu_*)"

# Frames of 1 spp at 1080p on the GPU (issue 31's table): per sampler, scene and depth, the median
# of the frames after the warm-up and the per-stage medians (CUDA events), from rll interactive.
for scene in cornell-boxes-room arch-interior; do
  for depth in 1 5; do
    for sampler in power tree rll; do
      name="frames-$scene-$sampler-d$depth"
      if "$build/rll" interactive "builtin:$scene" --device cuda --sampler "$sampler" \
          --max-depth "$depth" --frames 12 --warmup 4 --stats "$logs/$name.json" \
          > "$logs/$name.log" 2>&1; then
        note "$name: $(grep '^median of' "$logs/$name.log" | head -1)"
      else
        failed=1
        note "$name: FAILED (log: $logs/$name.log)"
      fi
    done
  done
done

echo
echo "== rll GPU run: summary"
head -3 "$logs/devices.log"
printf '%s\n' "${summary[@]}"
[ $failed -eq 0 ] && echo "all passed" || echo "SOMETHING FAILED: see the logs above"
exit $failed
