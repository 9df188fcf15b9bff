#!/usr/bin/env bash
# Installs the Debian packages rll builds and tests with, only those that are missing.
# With --test, also what only the tests need (chromium, which loads the HTML reports).
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config libembree-dev libtbb-dev libopenexr-dev libstb-dev
      libtinyobjloader-dev libtinygltf-dev libcli11-dev nlohmann-json3-dev libfmt-dev libgtest-dev
      libbenchmark-dev libboost-dev python3)
if [ "${1:-}" = "--test" ]; then pkgs+=(chromium); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
echo "rll: installing missing Debian packages: ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
