#!/usr/bin/env bash
# What splitting a render over jobs costs, and what a learnt-state warm start saves (issue 15):
# cornell-boxes-room, one after another on this machine, so the figures are the total CPU time
# of all jobs (each a separate `rll render` process: scene load and BVH build included) plus the
# merge. Configurations, each at total budgets of T spp (BENCH_TOTALS, default 32 128 512):
#   tree-1      tree, one render of T spp
#   tree-4      tree, 4 shares of T/4 spp + rll merge
#   rll-1       rll, one render of T spp
#   rll-4-cold  rll, 4 shares of T/4 spp, each learning from scratch, + merge
#   rll-4-warm  rll, 4 shares of T/4 spp, each starting from a state learnt by one render of
#               BENCH_TRAIN spp (default 32; --rll-state-mode load), + merge; the training
#               render's time is reported apart (paid once per scene and resolution, not per
#               render)
# Errors against a cached reference (tree, halves, its noise subtracted: rll error
# --reference-variance); repeats with seeds 1..R interleave the configurations. Writes
# out/cluster-bench/results.tsv and prints the table of scripts/cluster_table.py.
#   scripts/cluster_bench.sh [BUILD] ; env: BENCH_RES (160x120), BENCH_INTEGRATOR (direct),
#   BENCH_REPEATS (3), BENCH_TOTALS, BENCH_TRAIN, BENCH_REF_SPP (512)
set -euo pipefail
build=${1:-build}
rll="$build/rll"
res=${BENCH_RES:-160x120}
integrator=${BENCH_INTEGRATOR:-direct}
repeats=${BENCH_REPEATS:-3}
totals=${BENCH_TOTALS:-"32 128 512"}
train=${BENCH_TRAIN:-32}
ref_spp=${BENCH_REF_SPP:-512}
scene=builtin:cornell-boxes-room
out=out/cluster-bench
mkdir -p "$out"
common=(--res "$res" --integrator "$integrator" --quiet)

now() { date +%s.%N; }
minus() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", a - b }'; }
plus() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", a + b }'; }
echo "cluster-bench: reference ($ref_spp spp, tree)"
"$rll" reference "$scene" "${common[@]}" --spp "$ref_spp" --sampler tree -o "$out/ref.exr" > "$out/ref.log" 2>&1 ||
  { cat "$out/ref.log"; exit 1; }

results="$out/results.tsv"
printf 'config\ttotal_spp\trepeat\tseconds\trender_seconds\tmerge_seconds\trelmse\ttrimmed_relmse\n' > "$results"
measure() {  # image -> "relmse trimmed"
  "$rll" error "$1" "$out/ref.exr" --reference-variance "$out/ref.variance.exr" --json |
    python3 -c 'import json,sys; j=json.load(sys.stdin); print(j["relmse"], j["trimmed_relmse"])'
}
render_seconds() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"])' "$1"; }

for r in $(seq 1 "$repeats"); do
  # The warm start's state, learnt once per repeat (its own seed, never one of the renders').
  state="$out/state.$r.rllstate"
  t0=$(now)
  "$rll" render "$scene" "${common[@]}" --sampler rll --spp "$train" --seed $((1000 + r)) \
    --rll-state "$state" --rll-state-mode save -o "$out/train.$r.exr" 2>> "$out/render.log"
  t1=$(now)
  printf 'train\t%s\t%s\t%s\t\t\t\t\n' "$train" "$r" "$(minus "$t1" "$t0")" >> "$results"
  for total in $totals; do
    share=$((total / 4))
    for config in tree-1 tree-4 rll-1 rll-4-cold rll-4-warm; do
      sampler=${config%%-*}
      img="$out/$config.$total.$r.exr"
      echo "cluster-bench: repeat $r, $config, $total spp"
      t0=$(now)
      rsec=0
      if [[ $config == *-1 ]]; then
        "$rll" render "$scene" "${common[@]}" --sampler "$sampler" --spp "$total" --seed "$r" \
          --stats "$out/stats.json" -o "$img" 2>> "$out/render.log"
        rsec=$(render_seconds "$out/stats.json")
        t1=$(now); tm=$t1
      else
        extra=()
        [ "$config" = rll-4-warm ] && extra=(--rll-state "$state" --rll-state-mode load)
        shares=()
        for i in 0 1 2 3; do
          s="$out/share.$i.exr"
          "$rll" render "$scene" "${common[@]}" --sampler "$sampler" --spp "$share" --seed "$r" \
            --task "$i/4" ${extra[@]+"${extra[@]}"} --stats "$out/stats.json" -o "$s" 2>> "$out/render.log"
          rsec=$(plus "$rsec" "$(render_seconds "$out/stats.json")")
          shares+=("$s")
        done
        tm=$(now)
        "$rll" merge "$img" "${shares[@]}" 2> "$out/merge.log"
        t1=$(now)
      fi
      read -r relmse trimmed < <(measure "$img")
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$config" "$total" "$r" "$(minus "$t1" "$t0")" "$rsec" \
        "$(minus "$t1" "$tm")" "$relmse" "$trimmed" >> "$results"
    done
  done
done
python3 scripts/cluster_table.py "$results"
