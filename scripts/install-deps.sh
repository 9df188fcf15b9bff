#!/usr/bin/env bash
# Installs the Debian packages rll builds and tests with, only those that are missing.
# With --test, also what only the tests need: chromium, which loads the HTML reports, and a
# single-node Slurm (slurmctld, slurmd, the client commands and munge) for the job-array test.
# Daemons that the packages' maintainer scripts would start are kept from starting (or stopped
# after the install), so a container without systemd is left as it was.
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config libembree-dev libtbb-dev libopenexr-dev libstb-dev
      libtinyobjloader-dev libtinygltf-dev libcli11-dev nlohmann-json3-dev libfmt-dev libgtest-dev
      libbenchmark-dev libboost-dev python3 zlib1g-dev python3-dev pybind11-dev python3-numpy
      python3-pytest python3-matplotlib librsvg2-dev libpango1.0-dev fonts-dejavu-core)
daemons=()
if [ "${1:-}" = "--test" ]; then
  pkgs+=(chromium slurmctld slurmd slurm-client munge)
  daemons=(munged slurmctld slurmd)
fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
echo "rll: installing missing Debian packages: ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive

# The daemons already running before the install are left alone; those the install starts are not.
before=""
for d in ${daemons[@]+"${daemons[@]}"}; do before+=" $(pgrep -x "$d" | tr "\n" " " || true)"; done
# policy-rc.d answering 101 tells invoke-rc.d not to start services; put one in only if none is there.
policy=/usr/sbin/policy-rc.d
own_policy=0
if [ ${#daemons[@]} -gt 0 ] && [ ! -e "$policy" ]; then
  printf '#!/bin/sh\nexit 101\n' | $sudo tee "$policy" >/dev/null
  $sudo chmod 755 "$policy"
  own_policy=1
fi
remove_policy() { if [ "$own_policy" = 1 ]; then $sudo rm -f "$policy"; fi; }
trap remove_policy EXIT

$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"

for d in ${daemons[@]+"${daemons[@]}"}; do
  for pid in $(pgrep -x "$d" || true); do
    case " $before " in *" $pid "*) ;; *) echo "rll: stopping $d (pid $pid) that the install started"
                                          $sudo kill "$pid" 2>/dev/null || true ;; esac
  done
done
