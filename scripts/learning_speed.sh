#!/usr/bin/env bash
# How far rll is from its oracle because it has learnt for too short a time: rll renders SPP
# samples per pixel starting from a state it learnt over N spp before (another seed; it goes on
# learning during the render), for each N; the oracle and a cold rll render the same SPP. Every
# image is measured against the same cached reference, its noise subtracted (`rll error
# --reference-variance`). docs/rll.md ("What is left of the gap to the oracle") has the figures.
# Usage: scripts/learning_speed.sh RLL SCENE OUT_DIR [extra render flags, e.g. --set rll.X=Y]
# Environment: INTEGRATOR (direct), RES (320x240), SPP (64), TRAIN ("4 16 64 256"),
# REF_SPP (512, rendered by rll, as the bench's), RLL_CACHE_DIR (the reference cache), CHAIN (0;
# 1: each state goes on learning from the previous one, over the difference of the TRAIN counts,
# which must increase: 4096 spp of learning cost 4096 spp, not the sum of the counts).
# Prints one line per render: what learnt before, relMSE, trimmed relMSE, ratio to the oracle's.
set -euo pipefail
rll=$1 scene=$2 out=$3
shift 3
integrator=${INTEGRATOR:-direct} res=${RES:-320x240} spp=${SPP:-64} train=${TRAIN:-"4 16 64 256"}
ref_spp=${REF_SPP:-512}
mkdir -p "$out"
trap 'echo "learning_speed.sh: a step failed; its messages are in $out/render.log" >&2' ERR
common=("builtin:$scene" --integrator "$integrator" --res "$res" --quiet)
"$rll" reference "${common[@]}" --sampler rll --spp "$ref_spp" -o "$out/ref.exr" > /dev/null
error() {  # relMSE and trimmed relMSE of an image
  "$rll" error "$1" "$out/ref.exr" --reference-variance "$out/ref.variance.exr" --json |
    python3 -c 'import json, sys; d = json.load(sys.stdin); print(d["relmse"], d["trimmed_relmse"])'
}
"$rll" render "${common[@]}" --sampler oracle --spp "$spp" --seed 1 -o "$out/oracle.exr" "$@" > /dev/null 2>> "$out/render.log"
read -r oracle oracle_trimmed < <(error "$out/oracle.exr")
line() {  # label, image
  read -r e t < <(error "$2")
  python3 -c "import sys; e, t, o, ot = map(float, sys.argv[2:]); print(f'{sys.argv[1]:>16}  relmse={e:.3e}  trimmed={t:.3e}  over the oracle: {e / o:.2f}x / {t / ot:.2f}x')" \
    "$1" "$e" "$t" "$oracle" "$oracle_trimmed"
}
line oracle "$out/oracle.exr"
"$rll" render "${common[@]}" --sampler rll --spp "$spp" --seed 1 -o "$out/cold.exr" "$@" > /dev/null 2>> "$out/render.log"
line "rll, cold" "$out/cold.exr"
previous=0
for n in $train; do
  rm -f "$out/state$n.bin"
  if [ "${CHAIN:-0}" = 1 ] && [ "$previous" -gt 0 ]; then
    # The seed differs per step, so that no step repeats the samples of an earlier one.
    cp "$out/state$previous.bin" "$out/state$n.bin"
    "$rll" render "${common[@]}" --sampler rll --spp "$((n - previous))" --seed "$((77 + n))" \
      -o "$out/train$n.exr" --rll-state "$out/state$n.bin" "$@" > /dev/null 2>> "$out/render.log"
  else
    "$rll" render "${common[@]}" --sampler rll --spp "$n" --seed 77 -o "$out/train$n.exr" \
      --rll-state "$out/state$n.bin" --rll-state-mode save "$@" > /dev/null 2>> "$out/render.log"
  fi
  previous=$n
  "$rll" render "${common[@]}" --sampler rll --spp "$spp" --seed 1 -o "$out/warm$n.exr" \
    --rll-state "$out/state$n.bin" --rll-state-mode load "$@" > /dev/null 2>> "$out/render.log"
  line "rll, after $n" "$out/warm$n.exr"
done
