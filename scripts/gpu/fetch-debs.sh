#!/usr/bin/env bash
# Run on a Debian 12 machine: downloads into .gpu-debs/ (git-ignored) the Debian packages of the
# libraries rll builds with that the GPU machine lacks (it reaches no package registry).
# scripts/gpu/run.sh unpacks them there. Packages already downloaded are kept (idempotent).
set -euo pipefail
cd "$(dirname "$0")/../.."
dir=.gpu-debs
pkgs=(libembree-dev libembree3-3 libtbb-dev libtbb12 libtbbmalloc2 libtbbbind-2-5 libopenexr-dev
      libopenexr-3-1-30 libimath-dev libimath-3-1-29 libtinyobjloader-dev libtinyobjloader2rc10
      libtinygltf-dev libtinygltf2d libstb-dev libstb0 nlohmann-json3-dev libfmt-dev libfmt9
      libcli11-dev libgtest-dev libbenchmark-dev libbenchmark1debian zlib1g-dev)
command -v apt-get > /dev/null || { echo "rll: fetch-debs.sh needs apt-get (a Debian 12 machine)" >&2; exit 1; }
mkdir -p "$dir"
missing=()
for p in "${pkgs[@]}"; do
  compgen -G "$dir/${p}_*.deb" > /dev/null || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "rll: downloading ${#missing[@]} packages into $dir/: ${missing[*]}"
  if ! (cd "$dir" && apt-get download "${missing[@]}"); then
    echo "rll: apt-get download failed (run 'apt-get update' first?)" >&2
    exit 1
  fi
fi
echo "rll: $dir/ holds the ${#pkgs[@]} packages ($(du -sh "$dir" | cut -f1)); on the GPU machine run scripts/gpu/run.sh"
