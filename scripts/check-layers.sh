#!/usr/bin/env bash
# Checks the layers of src/rll (DESIGN 4 and 6): a file may include headers of its own folder and
# of folders in lower layers only, so that no dependency runs back up. Prints every include that
# breaks the order and exits 1; prints the include counts between folders with --graph.
# Usage: check-layers.sh [--graph] [SOURCE_DIR]
set -euo pipefail
graph=0
if [ "${1:-}" = "--graph" ]; then graph=1; shift; fi
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root/src/rll"
# Lower numbers are lower layers; folders in one layer may not include each other.
declare -A layer=(
  [core]=0
  [scene]=1
  [accel]=2 [bvh]=2 [io]=2 [lighttree]=2
  [learn]=3
  [lights]=4
  [render]=5
  [wavefront]=6
  [cuda]=7
  [session]=8
  [eval]=9
)
status=0
declare -A count=()
for dir in */; do
  dir=${dir%/}
  if [ -z "${layer[$dir]+x}" ]; then
    echo "check-layers: src/rll/$dir has no layer: add it to scripts/check-layers.sh" >&2
    status=1
    continue
  fi
  while IFS=: read -r file line target; do
    [ "$target" = "$dir" ] && continue
    if [ -z "${layer[$target]+x}" ]; then
      echo "src/rll/$file:$line includes rll/$target/, a folder with no layer" >&2
      status=1
    elif [ "${layer[$target]}" -ge "${layer[$dir]}" ]; then
      echo "src/rll/$file:$line: $dir (layer ${layer[$dir]}) includes rll/$target/ (layer ${layer[$target]}): an arrow up or sideways" >&2
      status=1
    fi
    count["$dir -> $target"]=$(( ${count["$dir -> $target"]:-0} + 1 ))
  done < <(grep -rnoE '^#include "rll/[a-z_]+/' "$dir" | sed -E 's|^([^:]+):([0-9]+):#include "rll/([a-z_]+)/$|\1:\2:\3|')
done
if [ "$graph" = 1 ]; then
  for k in "${!count[@]}"; do echo "${count[$k]} $k"; done | sort -k2
fi
if [ "$status" = 0 ]; then echo "check-layers: no include runs up a layer"; fi
exit $status
