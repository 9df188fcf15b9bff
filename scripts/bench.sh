#!/usr/bin/env bash
# `make bench`: the benchmark suite. Equal-time comparisons of every sampler on the paper's
# scenes (median of 3 interleaved runs), equal-spp runs for the gap to the oracle, the
# ablation from paper-faithful settings to rll's defaults, the per-sample noise of `tree`
# against pbrt-v4's figures (seed to seed), the renderer's ray rate against a bare Embree loop
# and the samplers' per-call costs. The `tree` of rll's first version (commit $V1_COMMIT, its
# renderer: light sampling only, independent points, a Morton LBVH mixing sky and lamps) is
# built once under build-v1/ and run beside the current samplers, on the same reference.
# Rewrites bench/RESULTS.md; every report stays under out/bench/. Takes about two hours on 2
# cores; BENCH_QUICK=1 checks the pipeline in a few minutes (its figures mean nothing);
# BENCH_V1=0 skips the first version; BENCH_RES, BENCH_SECONDS, BENCH_REF_DIRECT, BENCH_REF_PATH and
# BENCH_REF_SAMPLER (default rll) override the resolution, the budget and the references;
# BENCH_SAMPLERS the equal-time comparisons' samplers; BENCH_SCENES limits the equal-time,
# resampling and equal-spp comparisons to some of the paper's scenes and BENCH_NEW_SCENES the new
# scenes' (default: all; a scene left out keeps its previous figures only where its part did not
# run, so a partial run says so in RESULTS.md's settings line).
set -euo pipefail
build=${1:-build}
rll="$build/rll"
out=out/bench
mkdir -p "$out"
if [ "${BENCH_QUICK:-0}" = 1 ]; then
  res=96x72; seconds=2; repeats=1; ref_direct=64; ref_path=32; spp_direct=8; spp_path=4; frames=2
  long_seconds=4
else
  res=320x240; seconds=10; repeats=3; ref_direct=2048; ref_path=1024; spp_direct=64; spp_path=32; frames=3
  long_seconds=120
fi
# BENCH_PARTS picks what runs (default: all of them); a part left out keeps its section of
# RESULTS.md from the previous run, marked as not re-measured.
parts=${BENCH_PARTS:-"equal-time ris long new-scenes equal-spp ablation seed-to-seed rays samplers"}
want() { [[ " $parts " == *" $1 "* ]]; }
ref_direct=${BENCH_REF_DIRECT:-$ref_direct}; ref_path=${BENCH_REF_PATH:-$ref_path}
res=${BENCH_RES:-$res}; seconds=${BENCH_SECONDS:-$seconds}; ref_sampler=${BENCH_REF_SAMPLER:-rll}
# rht twice: rll's tuned setting (docs/rht.md) and the study's own (gamma 0.025, 16 first-stage
# reservoirs, 1 shadow ray, as the study's README states); the report takes the better as the peer.
rht_study=rht:gamma=0.025:reservoirs=16:samples=1
samplers=${BENCH_SAMPLERS:-power,tree,fermat,ltc,rht,$rht_study,rll,oracle}
paper_scenes=${BENCH_SCENES:-"cornell-boxes-room arch-interior many-lights-open cornell-boxes-dynamic"}
new_scenes=${BENCH_NEW_SCENES:-"spot-hall screen-hall"}
V1_COMMIT=a3cbdd4
v1="build-v1/rll"
if [ "${BENCH_V1:-1}" = 1 ] && [ ! -x "$v1" ]; then
  echo "bench: building rll's first version ($V1_COMMIT) under build-v1/"
  rm -rf build-v1/src && mkdir -p build-v1/src
  git archive "$V1_COMMIT" | tar -x -C build-v1/src
  cmake -S build-v1/src -B build-v1 -G Ninja -DCMAKE_BUILD_TYPE=Release -DRLL_TESTS=OFF -DRLL_BENCH=OFF > /dev/null
  cmake --build build-v1 --target rll_cli -j "$(nproc)" > /dev/null
fi
# The reference: rendered once per scene and integrator with rll (unbiased, tested against
# power and tree) and cached under out/cache. Its seed differs from every compared run, so its
# noise adds the same variance to every sampler's error and favours none; rll is used because,
# at the same cost, its reference is the least noisy on the occluded scenes, which keeps the
# ratios from being compressed towards 1 by reference noise.
common=(--res "$res" --reference-sampler "$ref_sampler" --quiet)
# BENCH_RESUME=1 keeps a comparison whose summary.json a run of this script already wrote (its
# reference noise measured, every sampler asked for present): an interrupted suite goes on where
# it stopped.
done_already() {  # name, then compare arguments
  local name=$1; shift
  [ "${BENCH_RESUME:-0}" = 1 ] && [ -f "$out/$name/summary.json" ] || return 1
  local want_samplers=""
  while [ $# -gt 0 ]; do [ "$1" = --samplers ] && want_samplers=$2; shift; done
  python3 - "$out/$name/summary.json" "$want_samplers" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
have = {s["name"] for s in j.get("samplers", [])}
ok = "noise_relmse" in j.get("reference", {}) and set(sys.argv[2].split(",")) <= have
sys.exit(0 if ok else 1)
PY
}
run() {  # name, then compare arguments
  local name=$1; shift
  if done_already "$name" "$@"; then echo "bench: $name (kept from the last run)"; return 0; fi
  echo "bench: $name"
  "$rll" compare "$@" "${common[@]}" --repeats "${RUN_REPEATS:-$repeats}" --out "$out/$name" > "$out/$name.txt" 2>&1 || { cat "$out/$name.txt"; exit 1; }
}
run_v1() {  # name of a finished comparison, then compare arguments: v1's tree on its reference
  local name=$1; shift
  [ "${BENCH_V1:-1}" = 1 ] || return 0
  echo "bench: $name (first version's tree)"
  "$v1" compare "$@" --samplers tree --res "$res" --repeats "$repeats" --quiet \
    --reference "$out/$name/reference.exr" --out "$out/$name-v1" > "$out/$name-v1.txt" 2>&1 ||
    { cat "$out/$name-v1.txt"; exit 1; }
}
for scene in $paper_scenes; do
  f=1; [ $scene = cornell-boxes-dynamic ] && f=$frames
  if want equal-time; then
  run "$scene-direct" builtin:$scene --integrator direct --samplers $samplers --time $seconds --frames $f --reference-spp $ref_direct
  run_v1 "$scene-direct" builtin:$scene --integrator direct --time $seconds --frames $f
  run "$scene-path" builtin:$scene --integrator path --samplers $samplers --time $seconds --frames $f --reference-spp $ref_path
  run_v1 "$scene-path" builtin:$scene --integrator path --time $seconds --frames $f
  fi
  # Resampled next-event estimation (docs/nee.md): tree and rll with and without four candidates
  # (sampler variants carrying nee.candidates), rll also with the learnt target at four and two
  # candidates, beside rht, in one interleaved compare on the same cached reference.
  # BENCH_RIS_SCENES limits it to some scenes (default: all four).
  if want ris && [[ " ${BENCH_RIS_SCENES:-$scene} " == *" $scene "* ]]; then
  ris=tree,tree:nee.candidates=4,rll,rll:nee.candidates=4,rll:nee.candidates=4:nee.target=learnt,rll:nee.candidates=2:nee.target=learnt,rht,$rht_study
  run "$scene-direct-ris" builtin:$scene --integrator direct --samplers $ris --time $seconds --frames $f --reference-spp $ref_direct
  run "$scene-path-ris" builtin:$scene --integrator path --samplers $ris --time $seconds --frames $f --reference-spp $ref_path
  fi
  want equal-spp || continue
  run "$scene-direct-spp" builtin:$scene --integrator direct --samplers oracle,rll,tree,power --spp $spp_direct --frames $f --reference-spp $ref_direct
  run "$scene-path-spp" builtin:$scene --integrator path --samplers oracle,rll,tree,power --spp $spp_path --frames $f --reference-spp $ref_path
done
# Long renders: the study's winner (rht) against tree and rll over $long_seconds s per sampler, one
# run each, path, on the two scenes where visibility matters most (the same cached references).
want long && for scene in cornell-boxes-room arch-interior; do
  RUN_REPEATS=1 run "long-$scene-path" builtin:$scene --integrator path --samplers tree,rht,$rht_study,rll --time $long_seconds --reference-spp $ref_path
done
# The scenes of issue 32: 102,400 spot lights in occluded rooms (spot-hall) and large textured
# emitters beside small lamps (screen-hall), equal time, path.
want new-scenes && for scene in $new_scenes; do
  run "$scene-path" builtin:$scene --integrator path --samplers power,tree,ltc,rht,$rht_study,rll --time $seconds --reference-spp $ref_path
done
# Ablation: from the published RLL (`fermat`, docs/fermat.md) to rll's defaults, each row
# adding one of rll's changes to the row above; the last row differs from rll's defaults only
# in fermat's remaining settings (cut size, splits, jitter, reset, cell size, cold cells).
a1=fermat:reward=cluster
a2=$a1:target=moment
a3=$a2:learning=shrinkage:alpha=0.02
a4=$a3:prior=importance:split_by=importance:epsilon=0.1:trust=256:q_init=-1
a5=$a4:within=tree
ablation="tree,fermat,$a1,$a2,$a3,$a4,$a5,rll"
want ablation && for scene in cornell-boxes-room arch-interior; do
  run "ablation-$scene" builtin:$scene --integrator direct --samplers "$ablation" --time $seconds --reference-spp $ref_direct
done
# Per-sample noise of `tree`, measured as pbrt-v4's was (shared/PEERS.md): the relMSE of one
# seed's render against another's, 1024 spp, 160x120, direct lighting; with the renderer's
# defaults (MIS, Sobol'), with independent points, with light sampling only (v1's renderer) and
# v1's own binary.
s2s_spp=1024; [ "${BENCH_QUICK:-0}" = 1 ] && s2s_spp=16
want seed-to-seed && for scene in cornell-boxes-room arch-interior; do
  echo "bench: seed to seed, $scene"
  d="$out/seed-to-seed-$scene"
  SPP=$s2s_spp scripts/seed_to_seed.sh "$rll" "$scene" tree "$d-default" > "$d-default.txt"
  SPP=$s2s_spp scripts/seed_to_seed.sh "$rll" "$scene" tree "$d-independent" --points independent > "$d-independent.txt"
  SPP=$s2s_spp scripts/seed_to_seed.sh "$rll" "$scene" tree "$d-nee" --points independent --set direct.strategy=nee > "$d-nee.txt"
  if [ "${BENCH_V1:-1}" = 1 ]; then SPP=$s2s_spp scripts/seed_to_seed.sh "$v1" "$scene" tree "$d-v1" > "$d-v1.txt"; fi
done
if want rays; then
  echo "bench: ray rate"
  "$build/bench/rll_bench_rays" builtin:cornell-boxes-room power 4 > "$out/rays-power.txt"
  "$build/bench/rll_bench_rays" builtin:cornell-boxes-room rll 4 > "$out/rays-rll.txt"
fi
if want samplers; then
  echo "bench: sampler costs"
  min_time=0.3; [ "${BENCH_QUICK:-0}" = 1 ] && min_time=0.02
  "$build/bench/rll_bench_samplers" --benchmark_min_time=$min_time --benchmark_repetitions=3 \
    --benchmark_report_aggregates_only=true --benchmark_format=json > "$out/samplers.json"
fi
python3 scripts/bench_report.py "$out" bench/RESULTS.md \
  "res=$res seconds=$seconds repeats=$repeats references=${ref_direct}/${ref_path} spp (direct/path) scenes=${paper_scenes// /,}+${new_scenes// /,} parts=$parts"
echo "bench: wrote bench/RESULTS.md"
