#!/usr/bin/env bash
# Equal time of rll with resampled candidates from one cluster (nee.draw=cluster, docs/nee.md)
# beside rll, tree and rht (bench/RESULTS.md, "Candidates from one cluster"): spot-hall (path,
# M = 2, 4, 8 and both rht settings), then cornell-boxes-room (path), many-lights-open (path) and
# arch-interior (direct) at M = 4. 10 s a run, 3 repeats, 320x240, the bench's references (rll,
# 1024 spp path, 2048 direct), rendered into the cache on first use. Run it on a quiet machine.
#
#   scripts/cluster_draw_bench.sh [BUILD_DIR] [OUT_DIR]    (defaults: build, out/cluster-draw-bench)
#
# SECONDS_PER_RUN, REPEATS, RES and CACHE override the budget, repeats, resolution and cache.
set -euo pipefail
build=${1:-build}
out=${2:-out/cluster-draw-bench}
rll="$build/rll"
seconds=${SECONDS_PER_RUN:-10}
repeats=${REPEATS:-3}
res=${RES:-320x240}
cache=${CACHE:-out/cache}
[ -x "$rll" ] || { echo "cluster_draw_bench: no rll at $rll (build it first: make build)" >&2; exit 1; }
mkdir -p "$out"
common=(--res "$res" --reference-sampler rll --cache-dir "$cache" --time "$seconds"
        --repeats "$repeats" --quiet)
c2=rll:nee.candidates=2:nee.draw=cluster
c4=rll:nee.candidates=4:nee.draw=cluster
c8=rll:nee.candidates=8:nee.draw=cluster
rht_study=rht:gamma=0.025:reservoirs=16:samples=1
uptime > "$out/load.txt"
echo "cluster_draw_bench: spot-hall, path"
"$rll" compare builtin:spot-hall --integrator path --reference-spp 1024 "${common[@]}" \
  --samplers "tree,rht,$rht_study,rll,$c2,$c4,$c8" --out "$out/spot-hall-path"
uptime >> "$out/load.txt"
for s in cornell-boxes-room:path:1024 many-lights-open:path:1024 arch-interior:direct:2048; do
  IFS=: read -r scene integrator ref <<< "$s"
  echo "cluster_draw_bench: $scene, $integrator"
  "$rll" compare "builtin:$scene" --integrator "$integrator" --reference-spp "$ref" "${common[@]}" \
    --samplers "tree,rll,$c4" --out "$out/$scene-$integrator"
  uptime >> "$out/load.txt"
done
echo "cluster_draw_bench: reports under $out (load averages in $out/load.txt)"
