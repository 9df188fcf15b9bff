#!/usr/bin/env bash
# ReSTIR DI measured (issue 47, docs/restir.md): the bias of its variants over seeds, as
# scripts/psf_study.sh measures the filter's. SEEDS (16) renders of SPP (16) spp each (every
# sample one ReSTIR frame: temporal reuse within the render) of cornell-boxes-room, path, with
# restir:source=tree in its unbiased (Alg. 6) and biased (1 / sum M) variants, with and without
# reuse, and plain tree beside them; per pixel the mean over seeds against a cached reference
# gives the bias (relative squared bias as relMSE weighs it, the mean's own noise taken out, and
# the image's signed relative bias), the spread over seeds the variance.
# Usage: scripts/restir_study.sh RLL OUT_DIR [--tiny]
#   --tiny: 64x48, 4 spp, 4 seeds, reference 256 spp (checks that the script works; its figures
#   mean little). Env: RES, SPP, SEEDS, REF_SPP, CACHE, SCENE, SOURCE override; PYTHONPATH must
#   reach the rll module (build/python), run by $PYTHON (default /usr/bin/python3, with numpy).
set -euo pipefail
rll=$(realpath "$1") out=$2
tiny=${3:-}
if [ "$tiny" = "--tiny" ]; then
  res=${RES:-64x48} spp=${SPP:-4} seeds=${SEEDS:-4} ref_spp=${REF_SPP:-256}
else
  res=${RES:-320x240} spp=${SPP:-16} seeds=${SEEDS:-16} ref_spp=${REF_SPP:-4096}
fi
scene=${SCENE:-cornell-boxes-room} source=${SOURCE:-tree}
mkdir -p "$out"
cache=${CACHE:-$out/cache}
"$rll" reference "builtin:$scene" --spp "$ref_spp" --res "$res" --integrator path --quiet \
  --cache-dir "$cache" -o "$out/reference.exr" > /dev/null 2>&1
variants=("$source" "restir:source=$source" "restir:source=$source:weights=biased"
  "restir:source=$source:temporal=off" "restir:source=$source:temporal=off:weights=biased"
  "restir:source=$source:temporal=off:spatial=0")
for ((v = 0; v < ${#variants[@]}; ++v)); do
  for ((s = 1; s <= seeds; ++s)); do
    "$rll" render "builtin:$scene" --sampler "${variants[v]}" --spp "$spp" --res "$res" \
      --seed "$s" --quiet -o "$out/v$v.s$s.exr"
  done
done
"${PYTHON:-/usr/bin/python3}" - "$(dirname "$0")" "$out" "$seeds" "$scene" "$spp" \
  "${variants[@]}" <<'PY' | tee "$out/bias.md"
import sys
import numpy as np
import rll
sys.path.insert(0, sys.argv[1])
from seed_bias import over_seeds
d, seeds, scene, spp = sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
variants = sys.argv[6:]
ref = rll.read_exr(f"{d}/reference.exr").astype(np.float64)
print(f"{scene}, path, {spp} spp, {seeds} seeds: per pixel the mean over seeds against the "
      "reference (bias^2, the mean's own noise taken out) and the variance over seeds, relative "
      "as relMSE (means over pixels and channels); the image mean's relative bias with its "
      "standard error over seeds\n")
print("| sampler | relative bias^2 | relative variance | relMSE of one render | "
      "image bias (%) |")
print("|---|---|---|---|---|")
for v, name in enumerate(variants):
    r = over_seeds([rll.read_exr(f"{d}/v{v}.s{s}.exr") for s in range(1, seeds + 1)], ref)
    print(f"| {name} | {r['bias2']:.4g} | {r['variance']:.4g} | {r['one']:.4g} | "
          f"{100 * r['image_bias']:+.2f} +- {100 * r['image_bias_se']:.2f} |")
PY
