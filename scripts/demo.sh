#!/usr/bin/env bash
# `make demo`: compares light samplers on the paper's many-light scene at equal time, prints the
# table and says where the HTML report is. RLL_DEMO_SAMPLERS picks the samplers (default
# power,tree,rll; names this build does not have are skipped, and other samplers fill in so that
# at least two are compared), RLL_DEMO_SECONDS the time per sampler.
set -euo pipefail
build=${1:-build}
rll="$build/rll"
wanted=${RLL_DEMO_SAMPLERS:-power,tree,rll}
seconds=${RLL_DEMO_SECONDS:-20}
scene=builtin:cornell-boxes-room
out=out/demo

mapfile -t available < <("$rll" samplers)
has() { local n; for n in "${available[@]}"; do [ "$n" = "$1" ] && return 0; done; return 1; }
picked=()
IFS=',' read -ra names <<< "$wanted"
for s in "${names[@]}"; do
  if has "$s"; then picked+=("$s"); else echo "demo: sampler '$s' is not in this build; skipped"; fi
done
for s in "${available[@]}"; do
  [ ${#picked[@]} -ge 2 ] && break
  [[ " ${picked[*]} " == *" $s "* ]] || picked+=("$s")
done
samplers=$(IFS=,; echo "${picked[*]}")

# The reference: tree sampling (no learning state to distrust), rendered once (a few minutes on
# 2 cores) and then reused from out/cache. 320x240 keeps the first demo short.
echo "demo: comparing $samplers on $scene at 320x240, $seconds s each (the first demo also renders"
echo "      a 1024 spp reference, a few minutes; later ones reuse it from out/cache)"
"$rll" compare "$scene" --res 320x240 --integrator path --samplers "$samplers" --time "$seconds" \
  --reference-spp 1024 --reference-sampler tree --out "$out"
echo "demo: report at $out/report.html"
