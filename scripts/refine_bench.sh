#!/usr/bin/env bash
# rll with finer cells where the light changes (rll.refine, docs/rll.md "Finer cells where the
# light changes") against rll without (bench/RESULTS.md, "Finer cells where the light changes"):
# spot-hall (path, direct), cornell-boxes-room and arch-interior (direct, path), many-lights-open
# (path); samplers rll, rll:refine=1 and rll:refine=2 in one compare per configuration, so that
# their repeats interleave (compare runs each repeat of every sampler before the next repeat).
# 320x240, the bench's references (rll, 1024 spp path, 2048 direct), rendered into the cache on
# first use. Equal time by default (10 s a run, 3 repeats): run it on a quiet machine.
#
#   scripts/refine_bench.sh [BUILD_DIR] [OUT_DIR]    (defaults: build, out/refine-bench)
#
# SECONDS_PER_RUN, REPEATS, RES and CACHE override the budget, repeats, resolution and cache;
# SPP=N measures at equal samples (N spp) instead of equal time; CONFIGS picks configurations
# (SCENE:INTEGRATOR:REFERENCE_SPP, space separated); SAMPLERS the samplers.
set -euo pipefail
build=${1:-build}
out=${2:-out/refine-bench}
rll="$build/rll"
seconds=${SECONDS_PER_RUN:-10}
repeats=${REPEATS:-3}
res=${RES:-320x240}
cache=${CACHE:-out/cache}
samplers=${SAMPLERS:-rll,rll:refine=1,rll:refine=2}
configs=${CONFIGS:-"spot-hall:path:1024 spot-hall:direct:2048 cornell-boxes-room:direct:2048
cornell-boxes-room:path:1024 arch-interior:direct:2048 arch-interior:path:1024
many-lights-open:path:1024"}
[ -x "$rll" ] || { echo "refine_bench: no rll at $rll (build it first: make build)" >&2; exit 1; }
budget=(--time "$seconds")
[ -n "${SPP:-}" ] && budget=(--spp "$SPP")
mkdir -p "$out"
common=(--res "$res" --reference-sampler rll --cache-dir "$cache" "${budget[@]}"
        --repeats "$repeats" --quiet)
uptime > "$out/load.txt"
for c in $configs; do
  IFS=: read -r scene integrator ref <<< "$c"
  echo "refine_bench: $scene, $integrator"
  "$rll" compare "builtin:$scene" --integrator "$integrator" --reference-spp "$ref" "${common[@]}" \
    --samplers "$samplers" --out "$out/$scene-$integrator"
  uptime >> "$out/load.txt"
done
echo "refine_bench: reports under $out (load averages in $out/load.txt)"
