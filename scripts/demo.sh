#!/usr/bin/env bash
# `make demo`: renders the paper's many-light scene and says where the image is.
set -euo pipefail
build=${1:-build}
mkdir -p out
"$build/rll" render builtin:cornell-boxes-room --integrator path --sampler power --spp 64 --time 60 \
  -o out/demo-cornell-boxes-room.png --stats out/demo-cornell-boxes-room.json
echo "demo: image at out/demo-cornell-boxes-room.png, statistics at out/demo-cornell-boxes-room.json"
