#!/usr/bin/env bash
# Seed-to-seed relMSE of one sampler: two renders of the same scene with different seeds, one
# measured against the other (`rll compare --reference`). This is how pbrt-v4's per-sample noise
# was measured in shared/PEERS.md (1024 spp, 160x120, direct lighting), so the figures compare.
# Usage: scripts/seed_to_seed.sh RLL SCENE SAMPLER OUT_DIR [extra render/compare flags...]
# Prints one line: scene, sampler, spp, relMSE, trimmed relMSE (where the binary reports it) and
# the seconds of one render.
set -euo pipefail
rll=$1 scene=$2 sampler=$3 out=$4
shift 4
spp=${SPP:-1024} res=${RES:-160x120} integrator=${INTEGRATOR:-direct}
mkdir -p "$out"
"$rll" render "builtin:$scene" --integrator "$integrator" --sampler "$sampler" --spp "$spp" --res "$res" \
  --seed 1 -o "$out/seed1.exr" --quiet --stats "$out/seed1.json" "$@" 2> "$out/render.log"
"$rll" compare "builtin:$scene" --integrator "$integrator" --samplers "$sampler" --spp "$spp" --res "$res" \
  --seed 2 --reference "$out/seed1.exr" --out "$out/compare" --quiet "$@" > "$out/compare.log" 2>&1
python3 - "$out" "$scene" "$sampler" "$spp" <<'PY'
import json, sys
out, scene, sampler, spp = sys.argv[1:5]
s = json.load(open(f"{out}/compare/summary.json"))["samplers"][0]
st = json.load(open(f"{out}/seed1.json"))
val = lambda k: s[k]["median"] if isinstance(s.get(k), dict) else s.get(k)
trimmed = val("trimmed_relmse")
print(f"{scene} {sampler} spp={spp} relmse={val('relmse'):.3e} "
      + (f"trimmed_relmse={trimmed:.3e} " if trimmed is not None else "")
      + f"seconds={st['seconds']:.1f}")
PY
