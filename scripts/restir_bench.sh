#!/usr/bin/env bash
# ReSTIR DI against rll, frame by frame (issue 47, docs/restir.md): on each scene, FRAMES frames
# per run with TIME seconds a frame (equal time per frame; learning and ReSTIR's reservoirs carry
# from frame to frame), every frame measured against that frame's own reference
# (`rll compare --every-frame`): tree, rll, and ReSTIR with power, tree and rll candidates.
# Writes per scene OUT/SCENE/ (compare's files), OUT/SCENE.frames.svg (the report's plot of error
# against frame) and OUT/restir.md (a table per scene: relMSE and trimmed relMSE of every
# sampler at every frame, and the goals' ratios); then the cost of each part per frame: `rll
# interactive` (1 spp a frame) of every sampler on each scene, the median ms of each stage over
# the frames after the first, in OUT/costs.md.
# Usage: scripts/restir_bench.sh RLL OUT_DIR [--tiny]
#   --tiny: 48x36, 3 frames, 0.1 s, reference 32 spp (checks that the script works; its figures
#   mean nothing). Env: SCENES (default "cornell-boxes-dynamic cornell-boxes-room
#   arch-interior"), RES (160x120), FRAMES (16), TIME (0.25 s), REF_SPP (1024), REPEATS (3),
#   INTEGRATOR (path), SAMPLERS (the six above, comma-separated), CACHE (the reference cache).
set -euo pipefail
rll=$(realpath "$1") out=$2
tiny=${3:-}
if [ "$tiny" = "--tiny" ]; then
  res=${RES:-48x36} frames=${FRAMES:-3} time=${TIME:-0.1} ref_spp=${REF_SPP:-32}
  repeats=${REPEATS:-1}
else
  res=${RES:-160x120} frames=${FRAMES:-16} time=${TIME:-0.25} ref_spp=${REF_SPP:-1024}
  repeats=${REPEATS:-3}
fi
scenes=${SCENES:-cornell-boxes-dynamic cornell-boxes-room arch-interior}
samplers=${SAMPLERS:-tree,rll,restir:source=power,restir:source=tree,restir:source=rll}
integrator=${INTEGRATOR:-path}
mkdir -p "$out"
cache=${CACHE:-$out/cache}
for scene in $scenes; do
  echo "== $scene: $samplers, $frames frames of $time s at $res ($(uptime))" >&2
  "$rll" compare "builtin:$scene" --samplers "$samplers" --time "$time" --frames "$frames" \
    --every-frame --repeats "$repeats" --res "$res" --integrator "$integrator" \
    --reference-spp "$ref_spp" --cache-dir "$cache" --out "$out/$scene" --quiet \
    > "$out/$scene.log" 2>&1 || { cat "$out/$scene.log" >&2; exit 1; }
  for spec in ${samplers//,/ }; do
    "$rll" interactive "builtin:$scene" --sampler "$spec" --frames "$frames" --res "$res" \
      --integrator "$integrator" --quiet --stats "$out/$scene.interactive.${spec//[:=]/_}.json"
  done
  # The plot of error against frame, as report.html embeds it.
  python3 - "$out/$scene/report.html" "$out/$scene.frames.svg" <<'PY'
import re, sys
html = open(sys.argv[1]).read()
m = re.search(r"<h2>Error per frame</h2>\s*<div class=\"plot\">(.*?)</div>", html, re.S)
if not m:
    sys.exit(f"{sys.argv[1]}: no plot of error against frame")
open(sys.argv[2], "w").write(m.group(1) + "\n")
PY
done
python3 - "$out" "$time" "$frames" "$res" $scenes <<'PY' | tee "$out/restir.md"
import json, sys
out, time, frames, res, scenes = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5:]
for scene in scenes:
    j = json.load(open(f"{out}/{scene}/summary.json"))
    ss = j["samplers"]
    print(f"### {scene}: {frames} frames, {time} s each, {res}, {j['repeats']} repeats\n")
    print("relMSE (trimmed relMSE) of each frame against its own reference, median over repeats; "
          "mean spp per frame in the header\n")
    print("| frame | " + " | ".join(f"{s['name']} ({s['mean_spp']['median']:.3g} spp)" for s in ss) + " |")
    print("|---|" + "---|" * len(ss))
    for f in range(frames):
        cells = []
        for s in ss:
            fr = s["frames"][f]
            cells.append(f"{fr['relmse']['median']:.3g} ({fr['trimmed_relmse']['median']:.3g})")
        print(f"| {f + 1} | " + " | ".join(cells) + " |")
    by = {s["name"]: s for s in ss}
    def last(name, key="relmse"):
        return by[name]["frames"][-1][key]["median"]
    def steady(name):  # the median relMSE over the second half of the frames
        v = sorted(fr["relmse"]["median"] for fr in by[name]["frames"][frames // 2:])
        return v[len(v) // 2]
    if "restir:source=rll" in by and "restir:source=tree" in by:
        print(f"\nReSTIR with rll candidates / with tree candidates, last frame: relMSE "
              f"{last('restir:source=rll') / last('restir:source=tree'):.3f}, trimmed "
              f"{last('restir:source=rll', 'trimmed_relmse') / last('restir:source=tree', 'trimmed_relmse'):.3f} "
              f"(goal: at most 0.5 on the occluded scenes)")
        print(f"ReSTIR with rll candidates / with tree candidates, median of the second half's "
              f"frames: {steady('restir:source=rll') / steady('restir:source=tree'):.3f}")
    if "rll" in by and "restir:source=rll" in by:
        print(f"rll alone / ReSTIR with rll candidates, last frame: "
              f"{last('rll') / last('restir:source=rll'):.3f}")
    print()
PY
python3 - "$out" "$res" "$samplers" $scenes <<'PY' | tee "$out/costs.md"
import json, sys
out, res, samplers, scenes = sys.argv[1], sys.argv[2], sys.argv[3].split(","), sys.argv[4:]
for scene in scenes:
    runs = {}
    for spec in samplers:
        tag = spec.replace(":", "_").replace("=", "_")
        runs[spec] = json.load(open(f"{out}/{scene}.interactive.{tag}.json"))
    stages = next(iter(runs.values()))["stages"]
    print(f"### {scene}: ms per frame at {res}, 1 spp, median over the frames after the first\n")
    print("| sampler | total | " + " | ".join(stages) + " |")
    print("|---|---|" + "---|" * len(stages))
    for spec, j in runs.items():
        s = j["summary"]
        print(f"| {spec} | {s['ms_total']['median']:.1f} | " +
              " | ".join(f"{s['ms_stages'][st]['median']:.2f}" for st in stages) + " |")
    print()
PY
