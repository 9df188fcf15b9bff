#!/usr/bin/env bash
# ctest slurm_job_array: scripts/slurm/render.sh on a real single-node Slurm.
#   slurm_test.sh RLL_BINARY SOURCE_DIR
# Starts munged, slurmctld and slurmd configured entirely in a fresh temporary directory (own munge
# key and socket, loopback ports that were free, state, spool, pid and log files), submits a 4-task
# render of builtin:cornell-box plus its merge job with render.sh, waits for both, and checks the
# merged image against one 16 spp render of the same scene; then checks that a share of another
# resolution is refused by `rll merge`, and that a failing task cancels the merge job. Everything
# it started is stopped and the directory removed on exit. Exits 77 (skipped) where Slurm or munge
# is not installed or cannot start.
set -euo pipefail

[ $# -eq 2 ] || { echo "usage: $0 RLL_BINARY SOURCE_DIR" >&2; exit 2; }
rll=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
src=$(cd "$2" && pwd)
render_sh="$src/scripts/slurm/render.sh"
export PATH="$PATH:/usr/sbin:/sbin"

say() { echo "slurm_test: $*"; }
skip() { say "SKIPPED: $*"; exit 77; }
fail() { show_logs; say "FAILED: $*"; exit 1; }

for c in munged mungekey slurmctld slurmd sbatch squeue sinfo scontrol scancel python3; do
  command -v "$c" >/dev/null 2>&1 ||
    skip "'$c' is not installed (scripts/install-deps.sh --test installs Slurm and munge)"
done
[ "$(id -u)" -eq 0 ] || skip "needs root: slurmd runs the jobs as SlurmUser=root"
[ -x "$rll" ] || fail "no rll program at $rll"

# A short path: munged's socket path must fit in a sockaddr_un (108 bytes).
tmp=$(mktemp -d /tmp/rll-slurm.XXXXXX)
chmod 711 "$tmp"
pids=()
cleanup() {
  local rc=$? pid i
  set +e
  if [ -f "$tmp/slurm.conf" ] && [ ${#pids[@]} -gt 0 ]; then
    # Jobs first (slurmstepd outlives slurmd), then the daemons, then munged.
    export SLURM_CONF="$tmp/slurm.conf"
    scancel --quiet --user "$(id -un)" 2>/dev/null
    for ((i = 0; i < 20; i++)); do
      [ -z "$(squeue -h 2>/dev/null)" ] && break
      sleep 0.5
    done
  fi
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2>/dev/null; done
  for pid in ${pids[@]+"${pids[@]}"}; do
    for ((i = 0; i < 50; i++)); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  rm -rf "$tmp"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP

show_logs() {
  local f
  for f in "$tmp"/*.log "$tmp"/work/logs/*.log "$tmp"/fail/logs/*.log; do
    [ -f "$f" ] || continue
    echo "----- ${f#"$tmp"/} (last 30 lines)"
    tail -n 30 "$f"
  done
}

# --- munge: its own key, socket, pid, seed and log (--force: it refuses root otherwise).
mungekey --create --keyfile="$tmp/munge.key" >/dev/null 2>&1 || skip "mungekey cannot create a key"
chmod 400 "$tmp/munge.key"
munged --foreground --force --socket="$tmp/munge.socket" --key-file="$tmp/munge.key" \
  --pid-file="$tmp/munged.pid" --seed-file="$tmp/munged.seed" --log-file="$tmp/munged.log" \
  >"$tmp/munged.out" 2>&1 &
pids+=($!)
for ((i = 0; i < 50; i++)); do [ -S "$tmp/munge.socket" ] && break; sleep 0.1; done
munge --socket="$tmp/munge.socket" --no-input 2>/dev/null |
  unmunge --socket="$tmp/munge.socket" >/dev/null 2>&1 ||
  { cat "$tmp/munged.out" "$tmp/munged.log" 2>/dev/null; skip "munged does not start here"; }

# --- slurm.conf: one node (this machine's CPUs), one partition, ports that are free now.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
cpus=$(nproc)
mem=$(($(awk '/^MemTotal:/ {print $2}' /proc/meminfo) / 1024 / 2))
mkdir -p "$tmp/state" "$tmp/spool"
cat >"$tmp/slurm.conf" <<EOF
ClusterName=rlltest
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge.socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=kill_invalid_depend
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
MailProg=/bin/true
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=rll Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -D -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N localhost -f "$SLURM_CONF" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
state=""
for ((i = 0; i < 120; i++)); do
  state=$(sinfo -h -N -n localhost -o %t 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
if [ "$state" != idle ]; then
  tail -n 20 "$tmp/slurmctld.out" "$tmp/slurmd.out"
  skip "the node did not come up idle within 60 s (state '$state'): Slurm cannot run here"
fi
say "Slurm is up on 127.0.0.1 (ports $ctld_port, $slurmd_port; $cpus CPUs)"

# Waits (at most $2 s) until none of the jobs $1 is pending or running.
wait_jobs() {
  local t
  for ((t = 0; t < $2 * 2; t++)); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 0.5
  done
  squeue -j "$1"
  fail "jobs $1 did not finish within $2 s"
}
# The JobState of job $1 (every task of an array, one a line).
job_states() { scontrol show job "$1" | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }

# --- A 4-task render and its merge, through render.sh.
cd "$tmp"
flags=(--res 64x48 --integrator direct --sampler tree --threads 1)
ids=$("$render_sh" --parsable --tasks 4 --spp 4 --rll "$rll" -o out/merged.exr --work work \
  --time 10 builtin:cornell-box -- "${flags[@]}") || fail "render.sh exited with $?"
read -r array_id merge_id <<<"$ids"
[[ $array_id =~ ^[0-9]+$ && $merge_id =~ ^[0-9]+$ ]] || fail "render.sh printed '$ids', not two job ids"
say "submitted render array $array_id and merge job $merge_id"
wait_jobs "$array_id,$merge_id" 300
states=$(job_states "$array_id" | sort | uniq -c | tr -s ' ')
[ "$states" = " 4 COMPLETED" ] || fail "render array tasks ended as: $states"
[ "$(job_states "$merge_id")" = COMPLETED ] || fail "merge job ended as $(job_states "$merge_id")"
for i in 0 1 2 3; do [ -s "work/share.$i.exr" ] || fail "no share $i"; done
[ -s out/merged.exr ] || fail "the merge job wrote no out/merged.exr"
merge_log=$(cat work/logs/merge."$merge_id".log)
grep -qw 16 <<<"$merge_log" || fail "the merge did not report 16 spp: $merge_log"
say "4 shares merged into a 16 spp image"

# --- The merged image is one 16 spp render, to float rounding.
"$rll" render builtin:cornell-box "${flags[@]}" --spp 16 -o single.exr --quiet ||
  fail "rll render of the single image failed"
# The merge job's image (a merged image merges again, alone), and the shares merged here.
"$rll" merge check.exr out/merged.exr --check-against single.exr ||
  fail "the merge job's image differs from one 16 spp render"
"$rll" merge check2.exr work/share.{0,1,2,3}.exr --check-against single.exr ||
  fail "the merged shares differ from one 16 spp render"
say "the merged image matches one 16 spp render"

# --- A share of another resolution is refused.
"$rll" render builtin:cornell-box --res 32x24 --integrator direct --sampler tree --threads 1 \
  --task 0/4 --spp 4 -o other.exr --quiet || fail "rll render of the 32x24 share failed"
if "$rll" merge bad.exr other.exr work/share.{1,2,3}.exr >refusal.txt 2>&1; then
  fail "rll merge accepted a 32x24 share with 64x48 ones"
fi
[ ! -e bad.exr ] || fail "rll merge refused the shares but wrote bad.exr"
grep -qiE 'res|width|height|size' refusal.txt ||
  fail "the refusal does not name the resolution: $(cat refusal.txt)"
say "a share of another resolution is refused: $(head -n 1 refusal.txt)"

# --- A failing task cancels the merge job instead of leaving it pending.
ids=$("$render_sh" --parsable --tasks 2 --spp 1 --rll "$rll" -o fail/never.exr --work fail \
  builtin:cornell-box -- --res 16x12 --sampler no-such-sampler) || fail "render.sh exited with $?"
read -r array_id merge_id <<<"$ids"
wait_jobs "$array_id,$merge_id" 120
job_states "$array_id" | grep -q FAILED || fail "the failing tasks ended as $(job_states "$array_id")"
[ "$(job_states "$merge_id")" = CANCELLED ] ||
  fail "after failed tasks the merge job is $(job_states "$merge_id")"
[ ! -e fail/never.exr ] || fail "the merge ran although the tasks failed"
say "failed tasks cancel the merge job"

say "passed"
