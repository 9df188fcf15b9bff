#!/usr/bin/env bash
# Samples per second of the wavefront renderer (traced by Embree, and by rll's BVH) against the
# megakernel, same run: each configuration renders megakernel then the two wavefronts, interleaved, `repeats` times; prints the ratio of
# their medians (on a shared machine only the ratio means anything).
# Usage: scripts/bench_wavefront.sh [RLL_BINARY] [SECONDS] [REPEATS]
set -euo pipefail
rll=${1:-build/rll}
seconds=${2:-4}
repeats=${3:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

rate() {  # samples per second of one render: rate SCENE SAMPLER [--wavefront]
  "$rll" render "builtin:$1" --res 320x240 --integrator path --sampler "$2" --time "$seconds" \
    --quiet -o "$tmp/image.exr" --stats "$tmp/stats.json" "${@:3}" >/dev/null 2>&1
  python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["samples_per_second"])' "$tmp/stats.json"
}

median() { sort -g | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

echo "| scene | sampler | wavefront / megakernel samples per second | wavefront traced by rll's BVH / megakernel |"
echo "|---|---|---|---|"
for scene in cornell-boxes-room arch-interior; do
  for sampler in power rll; do
    mega=() wave=() bvh=()
    for ((r = 0; r < repeats; ++r)); do
      mega+=("$(rate "$scene" "$sampler")")
      wave+=("$(rate "$scene" "$sampler" --wavefront)")
      bvh+=("$(rate "$scene" "$sampler" --wavefront --tracer bvh)")
    done
    m=$(printf '%s\n' "${mega[@]}" | median)
    w=$(printf '%s\n' "${wave[@]}" | median)
    b=$(printf '%s\n' "${bvh[@]}" | median)
    printf '| %s | %s | %.3f | %.3f |\n' "$scene" "$sampler" "$(echo "$w / $m" | bc -l)" \
      "$(echo "$b / $m" | bc -l)"
  done
done
