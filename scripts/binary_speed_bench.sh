#!/usr/bin/env bash
# Samples per second of two rll binaries that render the same images (a change that only makes
# sampling faster, as the light tree's descent steps: bench/RESULTS.md "Sampler costs"), at equal
# samples: for each scene, integrator and sampler, the two binaries' renders alternate (A B A B
# ...), and the script prints each one's median samples per second (the render's own figure in
# --stats: rendering only, not loading or the tree's build) and the median of the pairs' ratios
# B / A. Run it on a quiet machine.
#
#   scripts/binary_speed_bench.sh BINARY_A BINARY_B [OUT_DIR]    (default OUT_DIR: out/speed-bench)
#
# REPEATS (5), RES (320x240), SPP_DIRECT (32), SPP_PATH (16), SAMPLERS ("power tree rll") and
# SCENES ("cornell-boxes-room arch-interior many-lights-open spot-hall") override the defaults.
set -euo pipefail
[ $# -ge 2 ] || { sed -n '2,12p' "$0" >&2; exit 2; }
a=$1
b=$2
out=${3:-out/speed-bench}
for bin in "$a" "$b"; do
  [ -x "$bin" ] || { echo "binary_speed_bench: no rll binary at $bin" >&2; exit 1; }
done
repeats=${REPEATS:-5}
res=${RES:-320x240}
samplers=${SAMPLERS:-power tree rll}
scenes=${SCENES:-cornell-boxes-room arch-interior many-lights-open spot-hall}
mkdir -p "$out"
uptime > "$out/load.txt"
stat_of() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["samples_per_second"])' "$1"; }
printf '%-20s %-7s %-6s %12s %12s %8s\n' scene integ sampler "A samples/s" "B samples/s" "B/A"
for scene in $scenes; do
  for integrator in direct path; do
    spp=${SPP_DIRECT:-32}
    [ "$integrator" = path ] && spp=${SPP_PATH:-16}
    for sampler in $samplers; do
      ra=() rb=()
      for ((r = 0; r < repeats; ++r)); do
        for side in a b; do
          bin=$a
          [ "$side" = b ] && bin=$b
          "$bin" render "builtin:$scene" --integrator "$integrator" --sampler "$sampler" \
            --res "$res" --spp "$spp" --quiet -o "$out/img-$side.exr" \
            --stats "$out/stats-$side.json" > /dev/null 2>&1
          if [ "$side" = a ]; then ra+=("$(stat_of "$out/stats-a.json")"); else rb+=("$(stat_of "$out/stats-b.json")"); fi
        done
      done
      python3 - "$scene" "$integrator" "$sampler" "${ra[*]}" "${rb[*]}" <<'EOF'
import statistics, sys
scene, integrator, sampler, ra, rb = sys.argv[1:]
ra = [float(x) for x in ra.split()]
rb = [float(x) for x in rb.split()]
ratio = statistics.median(y / x for x, y in zip(ra, rb))
print(f"{scene:20s} {integrator:7s} {sampler:6s} {statistics.median(ra)/1e6:10.3f} M "
      f"{statistics.median(rb)/1e6:10.3f} M {ratio:8.3f}")
EOF
    done
  done
done | tee "$out/speed.txt"
uptime >> "$out/load.txt"
