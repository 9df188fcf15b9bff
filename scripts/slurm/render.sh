#!/usr/bin/env bash
# Renders one image on a Slurm cluster as a job array: task I of N renders share I (sample indices
# [I*S, (I+1)*S) of one N*S spp render) with `rll render --task I/N`, and a job that waits for all
# of them (afterok) merges the shares with `rll merge`. Run it on a login node; see --help and
# docs/cluster.md.
set -euo pipefail

prog=$(basename "$0")
script_dir=$(cd "$(dirname "$0")" && pwd)

usage() {
  cat <<EOF
Usage: $prog --tasks N --spp S -o OUT.exr [OPTIONS] SCENE [-- RENDER_FLAGS...]

Submits a Slurm job array of N tasks, each rendering S samples per pixel of SCENE (share I holds
sample indices [I*S, (I+1)*S) of one N*S spp render), and a merge job that starts once every task
has succeeded (--dependency=afterok) and averages the shares into OUT.exr. Merging gives the same
image as one \`rll render SCENE --spp N*S\` with the same flags and seed (for samplers that do not
learn; learning samplers learn within each share). Prints the two job ids.

Required:
  --tasks N            Number of array tasks (shares), N >= 1
  --spp S              Samples per pixel of each task (the merged image has N*S)
  -o, --output OUT     The merged image, an .exr file
  SCENE                What \`rll render\` takes: a scene file or builtin:NAME

Options:
  --rll BINARY         The rll program the jobs run (default: \`rll\` on PATH, else the build/rll
                       of this checkout); it must be reachable from the compute nodes
  --work DIR           Where the shares (share.I.exr), the generated job scripts and the Slurm
                       logs (logs/) go (default: OUT without .exr plus .shares, next to OUT)
  --partition P        Slurm partition for all jobs (default: the cluster's default)
  --cpus-per-task C    CPUs of each task; rll uses that many threads unless RENDER_FLAGS give
                       --threads (default: Slurm's, one CPU, so one thread)
  --time T             Slurm time limit of each job, as sbatch takes it (e.g. 30, 2:00:00)
  --rll-state FILE     Warm start of the rll sampler: each task starts from FILE when it exists
                       (a copy of it per task), and the merge job saves the state that share 0
                       learnt back to FILE, for the next frame or render of the same scene
  --parsable           Print only "ARRAY_JOB_ID MERGE_JOB_ID" (for scripts)
  -h, --help           This help
  -- RENDER_FLAGS...   Passed to every \`rll render\` (e.g. --sampler tree --res 640x480 --seed 7);
                       not --task, --spp, -o/--output, --rll-state or --frames, which this script
                       sets or does not support

Paths are made absolute, and the jobs run in the current directory (sbatch --chdir), so relative
paths in RENDER_FLAGS work on a shared file system. Other sbatch settings come from its SBATCH_*
environment variables (e.g. SBATCH_ACCOUNT, SBATCH_QOS, SBATCH_MEM_PER_CPU).

Example:
  $prog --tasks 4 --spp 256 -o out/frame.exr builtin:cornell-boxes-room -- --sampler tree
EOF
}

die() {
  echo "$prog: $*" >&2
  exit 2
}

# An option's value: "--opt VALUE" or "--opt=VALUE".
value() {
  local opt=$1
  shift
  [ $# -ge 1 ] || die "$opt needs a value (see --help)"
  [ -n "$1" ] || die "$opt needs a non-empty value"
  printf '%s' "$1"
}

positive_int() {
  [[ $2 =~ ^[0-9]+$ ]] && [ "$((10#$2))" -ge 1 ] 2>/dev/null ||
    die "$1 must be a positive whole number, not '$2'"
}

# An absolute path that need not exist yet (its parent directory is created).
absolute() {
  local dir base
  dir=$(dirname -- "$1")
  base=$(basename -- "$1")
  mkdir -p -- "$dir" || die "cannot create the directory '$dir'"
  printf '%s/%s' "$(cd -- "$dir" && pwd)" "$base"
}

tasks="" spp="" out="" rll="" work="" partition="" cpus="" time_limit="" state="" scene=""
parsable=0
extra=()
while [ $# -gt 0 ]; do
  arg=$1
  shift
  case $arg in
    -h | --help) usage; exit 0 ;;
    --tasks) tasks=$(value "$arg" "$@"); shift ;;
    --tasks=*) tasks=$(value --tasks "${arg#*=}") ;;
    --spp) spp=$(value "$arg" "$@"); shift ;;
    --spp=*) spp=$(value --spp "${arg#*=}") ;;
    -o | --output) out=$(value "$arg" "$@"); shift ;;
    --output=*) out=$(value --output "${arg#*=}") ;;
    --rll) rll=$(value "$arg" "$@"); shift ;;
    --rll=*) rll=$(value --rll "${arg#*=}") ;;
    --work) work=$(value "$arg" "$@"); shift ;;
    --work=*) work=$(value --work "${arg#*=}") ;;
    --partition) partition=$(value "$arg" "$@"); shift ;;
    --partition=*) partition=$(value --partition "${arg#*=}") ;;
    --cpus-per-task) cpus=$(value "$arg" "$@"); shift ;;
    --cpus-per-task=*) cpus=$(value --cpus-per-task "${arg#*=}") ;;
    --time) time_limit=$(value "$arg" "$@"); shift ;;
    --time=*) time_limit=$(value --time "${arg#*=}") ;;
    --rll-state) state=$(value "$arg" "$@"); shift ;;
    --rll-state=*) state=$(value --rll-state "${arg#*=}") ;;
    --parsable) parsable=1 ;;
    --) extra=("$@"); break ;;
    -*) die "unknown option '$arg' (see --help; rll render flags go after --)" ;;
    *)
      [ -z "$scene" ] || die "one scene only: '$scene' and '$arg' given (rll render flags go after --)"
      scene=$arg
      ;;
  esac
done

[ -n "$tasks" ] || die "--tasks N is required (see --help)"
[ -n "$spp" ] || die "--spp S is required (see --help)"
[ -n "$out" ] || die "-o OUT.exr is required (see --help)"
[ -n "$scene" ] || die "a SCENE is required (see --help)"
positive_int --tasks "$tasks"
positive_int --spp "$spp"
tasks=$((10#$tasks))
spp=$((10#$spp))
if [ -n "$cpus" ]; then
  positive_int --cpus-per-task "$cpus"
  cpus=$((10#$cpus))
fi
[[ $out == *.exr ]] || die "-o must name an .exr file (the shares are merged into it), not '$out'"
user_threads=0
for a in ${extra[@]+"${extra[@]}"}; do
  case $a in
    --task | --task=* | --spp | --spp=* | -o | -o* | --output | --output=*)
      die "'$a' after --: render.sh sets the share, its spp and its output itself" ;;
    --rll-state | --rll-state=*) die "give --rll-state before --: render.sh keeps one copy per task" ;;
    --frames | --frames=*) die "'$a': render.sh renders one frame; submit one array per frame" ;;
    --threads | --threads=*) user_threads=1 ;;
  esac
done

command -v sbatch >/dev/null 2>&1 ||
  die "sbatch not found: run this on a Slurm login node (without Slurm, see docs/cluster.md)"

# The rll program: --rll, else rll on PATH, else this checkout's build/rll.
if [ -z "$rll" ]; then
  if command -v rll >/dev/null 2>&1; then
    rll=$(command -v rll)
  elif [ -x "$script_dir/../../build/rll" ]; then
    rll="$script_dir/../../build/rll"
  else
    die "no rll program: none on PATH and no build/rll in this checkout; give --rll BINARY"
  fi
elif [[ $rll != */* ]]; then
  found=$(command -v -- "$rll") || die "--rll '$rll': no such program on PATH"
  rll=$found
fi
[ -f "$rll" ] && [ -x "$rll" ] || die "--rll '$rll' is not an executable file"
rll="$(cd -- "$(dirname -- "$rll")" && pwd)/$(basename -- "$rll")"
# An rll that runs here but predates shares would fail in every task: say so now. (One that does
# not run on the login node, e.g. built for the compute nodes only, is not checked.)
if help=$("$rll" render --help 2>&1); then
  [[ $help == *--task* ]] || die "$rll has no 'render --task' (too old?); give a newer one with --rll"
fi

out=$(absolute "$out")
[ -n "$work" ] || work="${out%.exr}.shares"
mkdir -p -- "$work/logs" || die "cannot create the work directory '$work'"
work=$(cd -- "$work" && pwd)
if [ -n "$state" ]; then
  state=$(absolute "$state")
fi
# A scene file is named by its absolute path; builtin:NAME and anything else is passed as given.
if [[ $scene != builtin:* ]] && [ -e "$scene" ]; then
  scene=$(absolute "$scene")
fi

# The job scripts: the settings as bash assignments (declare -p quotes them), then a fixed body.
render_job="$work/render.sbatch"
merge_job="$work/merge.sbatch"
{
  echo '#!/usr/bin/env bash'
  echo "# Written by $prog: one share of an rll render split over a Slurm job array."
  echo 'set -euo pipefail'
  declare -p rll scene tasks spp work state user_threads extra
  cat <<'EOF'
i=${SLURM_ARRAY_TASK_ID:?this script runs as a task of a Slurm job array}
flags=(--task "$i/$tasks" --spp "$spp" -o "$work/share.$i.exr" --quiet)
if [ "$user_threads" = 0 ]; then flags+=(--threads "${SLURM_CPUS_PER_TASK:-1}"); fi
if [ -n "$state" ]; then
  # Each task learns in its own copy: N tasks must not write one file at once.
  rm -f "$work/state.$i"
  if [ -e "$state" ]; then cp "$state" "$work/state.$i"; fi
  flags+=(--rll-state "$work/state.$i")
fi
echo "share $i of $tasks on $(hostname): $rll render $scene ${flags[*]} ${extra[*]+${extra[*]}}"
"$rll" render "$scene" "${flags[@]}" ${extra[@]+"${extra[@]}"}
EOF
} >"$render_job"
{
  echo '#!/usr/bin/env bash'
  echo "# Written by $prog: merges the shares of an rll render once every array task succeeded."
  echo 'set -euo pipefail'
  declare -p rll tasks work out state
  cat <<'EOF'
shares=()
for ((i = 0; i < tasks; i++)); do shares+=("$work/share.$i.exr"); done
"$rll" merge "$out" "${shares[@]}"
if [ -n "$state" ] && [ -s "$work/state.0" ]; then
  # Replaced in one rename, so a reader never sees half a file.
  cp "$work/state.0" "$state.tmp.$$"
  mv -f "$state.tmp.$$" "$state"
  echo "saved the rll state of share 0 to $state"
fi
echo "merged $tasks shares into $out"
EOF
} >"$merge_job"
chmod +x "$render_job" "$merge_job"

common=(--parsable --chdir "$PWD")
[ -z "$partition" ] || common+=(--partition "$partition")
[ -z "$time_limit" ] || common+=(--time "$time_limit")
render_opts=(--array "0-$((tasks - 1))" --job-name rll-render --output "$work/logs/render.%A_%a.log")
[ -z "$cpus" ] || render_opts+=(--cpus-per-task "$cpus")

# --parsable prints "ID" or "ID;CLUSTER".
array_id=$(sbatch "${common[@]}" "${render_opts[@]}" "$render_job") ||
  die "sbatch refused the render job array"
array_id=${array_id%%;*}
[[ $array_id =~ ^[0-9]+$ ]] || die "sbatch printed '$array_id', not a job id"
# kill-on-invalid-dep: if a task fails, the merge job is cancelled rather than pending forever.
if ! merge_id=$(sbatch "${common[@]}" --job-name rll-merge --output "$work/logs/merge.%j.log" \
  --dependency "afterok:$array_id" --kill-on-invalid-dep=yes "$merge_job"); then
  scancel "$array_id" 2>/dev/null || true
  die "sbatch refused the merge job (the render job array $array_id was cancelled)"
fi
merge_id=${merge_id%%;*}

if [ "$parsable" = 1 ]; then
  echo "$array_id $merge_id"
else
  echo "render job array: $array_id ($tasks tasks of $spp spp, $((tasks * spp)) spp in all)"
  echo "merge job:        $merge_id (after all tasks succeed) -> $out"
  echo "shares and logs:  $work"
fi
