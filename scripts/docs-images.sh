#!/usr/bin/env bash
# Renders the small pictures of the built-in scenes that docs/scenes.md shows (docs/images/).
set -euo pipefail
build=${1:-build}
mkdir -p docs/images
for scene in $("$build/rll" scenes | awk '{print $1}'); do
  spp=256
  [ "$scene" = many-lights-1m ] && spp=64
  "$build/rll" render "builtin:$scene" --res 240x180 --integrator path --sampler rll --spp "$spp" \
    --quiet -o "docs/images/$scene.png"
done
