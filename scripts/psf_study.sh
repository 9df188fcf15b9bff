#!/usr/bin/env bash
# Path-space filtering measured (issue 46, docs/psf.md): the teaser's table, the filter's bias
# against its width over seeds, and the samplers at equal time with the filter and its cost.
#   1. teaser: cornell-boxes-room, path, SPP (64) spp, power and rll, each unfiltered and with
#      --filter psf, against one cached unfiltered reference: relMSE, trimmed relMSE and MRSE of
#      each (two `rll compare` runs sharing the reference), and side-by-side pictures;
#   2. bias: SEEDS (16) renders of power with the filter at widths 3, 1.5 and 0.75 (1, 1/2, 1/4
#      of the default) and unfiltered: per pixel, the mean over seeds against the reference gives
#      the bias (relative squared bias, averaged over pixels), the spread over seeds the variance;
#   3. equal time: power, tree and rll with the filter at TIME (10) seconds on cornell-boxes-room,
#      arch-interior and many-lights-open, and the filter's cost as a share of the render time
#      (1 - its samples per second over the unfiltered render's, same sampler and time).
# Usage: scripts/psf_study.sh RLL OUT_DIR [--tiny]
#   --tiny: 64x48, 4 spp, 2 seeds, 1 s, reference 64 spp (checks that the script works; its
#   figures mean nothing). Env: RES, SPP, SEEDS, TIME, REF_SPP, CACHE, STEPS override; PYTHONPATH must reach
#   the rll module (build/python) for step 2, run by $PYTHON (default /usr/bin/python3, which
#   has numpy).
set -euo pipefail
rll=$(realpath "$1") out=$2
tiny=${3:-}
if [ "$tiny" = "--tiny" ]; then
  res=${RES:-64x48} spp=${SPP:-4} seeds=${SEEDS:-2} time=${TIME:-1} ref_spp=${REF_SPP:-64}
else
  res=${RES:-640x480} spp=${SPP:-64} seeds=${SEEDS:-16} time=${TIME:-10} ref_spp=${REF_SPP:-4096}
fi
mkdir -p "$out"
cache=${CACHE:-$out/cache}  # CACHE: a reference cache to reuse (the bench's out/cache at 320x240)
export RLL_CACHE_DIR="$cache"
common=(--res "$res" --integrator path --quiet --cache-dir "$cache" --reference-spp "$ref_spp")

# STEPS (default "teaser bias time") picks the steps that run.
steps=" ${STEPS:-teaser bias time} "
scene=cornell-boxes-room

# 1. The teaser.
if [[ $steps == *" teaser "* ]]; then
"$rll" compare "builtin:$scene" --samplers power,rll --spp "$spp" --out "$out/teaser-plain" \
  "${common[@]}" > "$out/teaser-plain.log" 2>&1
"$rll" compare "builtin:$scene" --samplers power,rll --spp "$spp" --filter psf \
  --out "$out/teaser-psf" "${common[@]}" > "$out/teaser-psf.log" 2>&1
python3 - "$out" "$scene" "$spp" <<'PY' | tee "$out/teaser.md"
import json, sys
out, scene, spp = sys.argv[1:4]
val = lambda s, k: s[k]["median"] if isinstance(s.get(k), dict) else s.get(k)
print(f"{scene}, path, {spp} spp, against an unfiltered reference\n")
print("| sampler | filter | relMSE | trimmed relMSE | MRSE |")
print("|---|---|---|---|---|")
rows = {}
for tag in ("plain", "psf"):
    for s in json.load(open(f"{out}/teaser-{tag}/summary.json"))["samplers"]:
        rows[(s["name"], tag)] = s
        print(f"| {s['name']} | {'psf' if tag == 'psf' else 'none'} | {val(s, 'relmse'):.4g} | "
              f"{val(s, 'trimmed_relmse'):.4g} | {val(s, 'mrse'):.4g} |")
r = lambda n, t: val(rows[(n, t)], "relmse")
print(f"\npsf power / psf rll relMSE: {r('power', 'psf') / r('rll', 'psf'):.2f}x (goal: >= 5x); "
      f"plain rll / psf rll: {r('rll', 'plain') / r('rll', 'psf'):.2f}x (goal: > 1)")
PY
fi

# 2. The bias against the width, over seeds (the reference of step 1, cached).
if [[ $steps == *" bias "* ]]; then
bias="$out/bias"
mkdir -p "$bias"
"$rll" reference "builtin:$scene" --spp "$ref_spp" --res "$res" --integrator path --quiet \
  --cache-dir "$cache" -o "$bias/reference.exr" > /dev/null 2>&1
for width in none 3 1.5 0.75; do
  for ((s = 1; s <= seeds; ++s)); do
    flags=()
    [ "$width" != none ] && flags=(--filter psf --set "psf.width=$width")
    "$rll" render "builtin:$scene" --sampler power --spp "$spp" --res "$res" --seed "$s" \
      --quiet -o "$bias/w$width.s$s.exr" "${flags[@]}"
  done
done
"${PYTHON:-/usr/bin/python3}" - "$(dirname "$0")" "$bias" "$seeds" <<'PY' | tee "$out/bias.md"
import sys
import numpy as np
import rll
sys.path.insert(0, sys.argv[1])
from seed_bias import over_seeds
d, seeds = sys.argv[2], int(sys.argv[3])
ref = rll.read_exr(f"{d}/reference.exr").astype(np.float64)
print(f"power, {seeds} seeds: per pixel the mean over seeds against the reference (bias^2) and "
      "the variance over seeds, relative as relMSE (means over pixels and channels)\n")
print("| psf.width | relative bias^2 | relative variance | relMSE of one render |")
print("|---|---|---|---|")
for width in ("none", "3", "1.5", "0.75"):
    r = over_seeds([rll.read_exr(f"{d}/w{width}.s{s}.exr") for s in range(1, seeds + 1)], ref)
    print(f"| {width} | {r['bias2']:.4g} | {r['variance']:.4g} | {r['one']:.4g} |")
PY
fi

# 3. Equal time, and the filter's cost (on a quiet machine: it times the renders).
[[ $steps == *" time "* ]] || exit 0
for scene in cornell-boxes-room arch-interior many-lights-open; do
  "$rll" compare "builtin:$scene" --samplers power,tree,rll --time "$time" --filter psf \
    --out "$out/time-$scene" "${common[@]}" > "$out/time-$scene.log" 2>&1
  for filter in none psf; do
    "$rll" render "builtin:$scene" --sampler power --time "$time" --spp 1000000 --res "$res" \
      --quiet --filter "$filter" -o "$out/cost-$scene-$filter.exr" \
      --stats "$out/cost-$scene-$filter.json"
  done
done
python3 - "$out" <<'PY' | tee "$out/time.md"
import json, sys
out = sys.argv[1]
val = lambda s, k: s[k]["median"] if isinstance(s.get(k), dict) else s.get(k)
print("| scene | sampler (psf) | relMSE | trimmed relMSE | MRSE | spp | filter's cost |")
print("|---|---|---|---|---|---|---|")
for scene in ("cornell-boxes-room", "arch-interior", "many-lights-open"):
    rate = {f: json.load(open(f"{out}/cost-{scene}-{f}.json"))["samples_per_second"]
            for f in ("none", "psf")}
    cost = 1 - rate["psf"] / rate["none"]
    for s in json.load(open(f"{out}/time-{scene}/summary.json"))["samplers"]:
        print(f"| {scene} | {s['name']} | {val(s, 'relmse'):.4g} | {val(s, 'trimmed_relmse'):.4g} "
              f"| {val(s, 'mrse'):.4g} | {val(s, 'mean_spp'):.1f} | {100 * cost:.1f}% |")
PY
