#!/usr/bin/env bash
# rll's error budget (issue 45 item 2, docs/rll.md "The error budget"): rll's relMSE at equal spp,
# and the same with one ideal component swapped in at a time (the study settings rll.ideal_*, and
# cells of half the size), for each scene, direct and path. The share of rll's relMSE that a
# component removes, (rll - swapped) / rll, is its part of the budget.
# Usage: scripts/error_budget.sh RLL OUT_DIR
# Env: SCENES (default "cornell-boxes-room arch-interior many-lights-open spot-hall"),
#   INTEGRATORS ("direct path"), RES (160x120), SPP (16; path renders SPP too), SEEDS (3: repeats,
#   seeds 1..SEEDS), CACHE (the reference cache, default OUT_DIR/cache; references by rll, 2048 spp
#   direct and 1024 path, rendered there if missing), LIGHT_RAYS (16: rll.ideal_light), POINTS
#   (64: rll.ideal_point), DIRECTIONS (64: rll.ideal_bsdf), POINT_RAYS (4: rll.ideal_light with
#   ideal_light_at=point), CONFIGS (default: rll cluster light lightpt point bsdf cells all;
#   `light` is the distribution at the cell's anchor, `lightpt` at each shading point (slow on
#   large clusters: spot-hall), `all` the cluster, the point and the BSDF side at once (not the
#   anchor's light, which adds error), the floor those leave: mostly the pixel's own noise, the
#   paths' bounces and the within-cluster choice).
# Writes OUT_DIR/SCENE-INTEGRATOR/ (each `rll compare` run) and OUT_DIR/budget.md (the table).
set -euo pipefail
rll=$(realpath "$1") out=$2
mkdir -p "$out"
out=$(realpath "$out")
scenes=${SCENES:-cornell-boxes-room arch-interior many-lights-open spot-hall}
integrators=${INTEGRATORS:-direct path}
res=${RES:-160x120} spp=${SPP:-16} seeds=${SEEDS:-3}
cache=${CACHE:-$out/cache}
light_rays=${LIGHT_RAYS:-16} points=${POINTS:-64} directions=${DIRECTIONS:-64}
point_rays=${POINT_RAYS:-4}
all_configs="rll cluster light lightpt point bsdf cells all"
configs=" ${CONFIGS:-$all_configs} "

# Each configuration as a sampler of `rll compare` (its label in the table first).
spec() {
  case $1 in
    rll) echo rll ;;
    cluster) echo rll:ideal_cluster=1 ;;
    light) echo "rll:ideal_light=$light_rays" ;;
    lightpt) echo "rll:ideal_light=$point_rays:ideal_light_at=point" ;;
    point) echo "rll:ideal_point=$points" ;;
    bsdf) echo "rll:ideal_bsdf=$directions" ;;
    # Cells of half the size: half the radius in footprints, half the cap.
    cells) echo rll:footprint_scale=2:max_cell=0.025 ;;
    all) echo "rll:ideal_cluster=1:ideal_point=$points:ideal_bsdf=$directions" ;;
  esac
}
samplers="" labels=""
for c in $all_configs; do
  if [[ $configs == *" $c "* ]]; then
    samplers+="${samplers:+,}$(spec "$c")"
    labels+="${labels:+,}$c"
  fi
done

for scene in $scenes; do
  for integrator in $integrators; do
    ref_spp=2048
    [ "$integrator" = path ] && ref_spp=1024
    dir="$out/$scene-$integrator"
    echo "$(date -u +%T) $scene $integrator: $samplers" >&2
    "$rll" compare "builtin:$scene" --integrator "$integrator" --samplers "$samplers" \
      --spp "$spp" --repeats "$seeds" --res "$res" --reference-sampler rll \
      --reference-spp "$ref_spp" --cache-dir "$cache" --out "$dir" --quiet > "$dir.log" 2>&1 ||
      { echo "failed: see $dir.log" >&2; tail -5 "$dir.log" >&2; exit 1; }
  done
done

python3 - "$out" "$spp" "$seeds" "$res" "$scenes" "$integrators" "$samplers" "$labels" <<'PY' | tee "$out/budget.md"
import json, sys
out, spp, seeds, res, scenes, integrators, samplers, labels = sys.argv[1:9]
samplers = samplers.split(",")
name = dict(zip(samplers, labels.split(","))).get
def runs(entry, key):
    # Each repeat's value (summary.json keeps them per run where it can, else the median).
    r = entry.get(key)
    if isinstance(r, dict):
        for k in ("values", "runs", "all"):
            if k in r: return list(r[k])
        return [r["median"]]
    return [r]
def median(v):
    v = sorted(v); n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])
print(f"relMSE at {spp} spp, {res}, {seeds} seeds (median; the range of the removed share over "
      "seeds in brackets, each seed's swapped run against the same seed's rll); removed share = "
      "(rll - swapped) / rll\n")
cols = [name(s) for s in samplers[1:]]
print("| scene | integrator | rll relMSE (trimmed) | " + " | ".join(cols) + " |")
print("|---|---|---|" + "---|" * len(cols))
for scene in scenes.split():
    for integ in integrators.split():
        summary = json.load(open(f"{out}/{scene}-{integ}/summary.json"))
        by = {s["name"]: s for s in summary["samplers"]}
        base = runs(by[samplers[0]], "relmse")
        tb = runs(by[samplers[0]], "trimmed_relmse")
        row = f"| {scene} | {integ} | {median(base):.3g} ({median(tb):.3g}) |"
        for s in samplers[1:]:
            v = runs(by[s], "relmse"); t = runs(by[s], "trimmed_relmse")
            shares = [(b - x) / b for b, x in zip(base, v)] if len(v) == len(base) else []
            tshare = (median(tb) - median(t)) / median(tb)
            spread = f" [{min(shares):+.0%}, {max(shares):+.0%}]" if len(shares) > 1 else ""
            row += f" {(median(base) - median(v)) / median(base):+.0%}{spread} (trimmed {tshare:+.0%}) |"
        print(row)
PY
