#!/usr/bin/env bash
# `make bench`: the benchmark suite. Equal-time comparisons of every sampler on the paper's
# scenes (median of 3 interleaved runs), equal-spp runs for the gap to the oracle, the
# ablation from paper-faithful settings to rll's defaults, the renderer's ray rate against a
# bare Embree loop and the samplers' per-call costs. Rewrites bench/RESULTS.md; every report
# stays under out/bench/. Takes about an hour on 2 cores; BENCH_QUICK=1 checks the pipeline in
# a few minutes (its figures mean nothing).
set -euo pipefail
build=${1:-build}
rll="$build/rll"
out=out/bench
mkdir -p "$out"
if [ "${BENCH_QUICK:-0}" = 1 ]; then
  res=96x72; seconds=2; repeats=1; ref_direct=64; ref_path=32; spp_direct=8; spp_path=4; frames=2
else
  res=320x240; seconds=10; repeats=3; ref_direct=2048; ref_path=1024; spp_direct=64; spp_path=32; frames=3
fi
samplers=power,tree,rll,oracle
# The reference: rendered once per scene and integrator with rll (unbiased, tested against
# power and tree) and cached under out/cache. Its seed differs from every compared run, so its
# noise adds the same variance to every sampler's error and favours none; rll is used because,
# at the same cost, its reference is the least noisy on the occluded scenes, which keeps the
# ratios from being compressed towards 1 by reference noise.
common=(--res "$res" --repeats "$repeats" --reference-sampler rll --quiet)
run() {  # name, then compare arguments
  local name=$1; shift
  echo "bench: $name"
  "$rll" compare "$@" "${common[@]}" --out "$out/$name" > "$out/$name.txt" 2>&1 || { cat "$out/$name.txt"; exit 1; }
}
for scene in cornell-boxes-room arch-interior many-lights-open cornell-boxes-dynamic; do
  f=1; [ $scene = cornell-boxes-dynamic ] && f=$frames
  run "$scene-direct" builtin:$scene --integrator direct --samplers $samplers --time $seconds --frames $f --reference-spp $ref_direct
  run "$scene-path" builtin:$scene --integrator path --samplers $samplers --time $seconds --frames $f --reference-spp $ref_path
  run "$scene-direct-spp" builtin:$scene --integrator direct --samplers oracle,rll,tree,power --spp $spp_direct --frames $f --reference-spp $ref_direct
  run "$scene-path-spp" builtin:$scene --integrator path --samplers oracle,rll,tree,power --spp $spp_path --frames $f --reference-spp $ref_path
done
# Ablation: each row adds one of rll's corrections to the paper-faithful settings.
a0=rll:within=uniform:reward=fullpdf:prior=power:split_by=power:defensive=cell:learning=exponential:jitter=1:footprint_scale=4:inherit=false
a1=${a0/reward=fullpdf/reward=cluster}
a2=${a1/within=uniform/within=tree}
a3=${a2/prior=power:split_by=power/prior=importance:split_by=importance}
a4=${a3/defensive=cell/defensive=tree}
a5=${a4/learning=exponential:/learning=shrinkage:}; a5=${a5/inherit=false/inherit=true}
ablation="tree,$a0,$a1,$a2,$a3,$a4,$a5,rll"
for scene in cornell-boxes-room arch-interior; do
  run "ablation-$scene" builtin:$scene --integrator direct --samplers "$ablation" --time $seconds --reference-spp $ref_direct
done
echo "bench: ray rate"
"$build/bench/rll_bench_rays" builtin:cornell-boxes-room power 4 > "$out/rays-power.txt"
"$build/bench/rll_bench_rays" builtin:cornell-boxes-room rll 4 > "$out/rays-rll.txt"
echo "bench: sampler costs"
min_time=0.3; [ "${BENCH_QUICK:-0}" = 1 ] && min_time=0.02
"$build/bench/rll_bench_samplers" --benchmark_min_time=$min_time --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_format=json > "$out/samplers.json"
python3 scripts/bench_report.py "$out" bench/RESULTS.md "res=$res seconds=$seconds repeats=$repeats"
echo "bench: wrote bench/RESULTS.md"
