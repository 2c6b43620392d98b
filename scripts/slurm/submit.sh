#!/bin/bash
# Renders one frame on a Slurm cluster: a job array of render tasks, each a tile or a share
# of the samples (render-array.sbatch), and a merge job after them that writes the image
# (merge.sbatch). README.md in this folder describes it.
#
#   submit.sh -o IMAGE --width W --height H --spp N [--tasks N] [--split tiles|samples]
#             [--parts DIR] [--gpus-per-task N] [--cltrace PATH] [--sbatch ARG]...
#             [SCENE] [-- CLTRACE_RENDER_FLAGS...]
#   submit.sh --rerun-failed PARTS [--sbatch ARG]...
set -euo pipefail

SCRIPTS=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

usage() {
    cat <<USAGE
usage: $0 -o IMAGE --width W --height H --spp N [--tasks N] [--split tiles|samples]
          [--parts DIR] [--gpus-per-task N] [--cltrace PATH] [--sbatch ARG]...
          [SCENE] [-- CLTRACE_RENDER_FLAGS...]
       $0 --rerun-failed PARTS [--sbatch ARG]...

  -o, --output IMAGE   the merged image; any format cltrace writes (.png, .exr, ...)
  --width, --height    the frame's size in pixels
  --spp N              samples per pixel
  --tasks N            render tasks in the job array (4)
  --split KIND         tiles: each task renders a tile of every sample (a grid of N tiles);
                       samples: each task renders every pixel, a share of the samples (tiles)
  --parts DIR          where the parts, job.conf and the logs go (IMAGE.parts); every node
                       must see it
  --gpus-per-task N    ask Slurm for N GPUs a task (--gres=gpu:N); cltrace then renders on
                       the task's GPU (--device gpu) unless the flags or CLTRACE_DEVICE pick
  --cltrace PATH       the cltrace binary the jobs run (cltrace on the PATH)
  --sbatch ARG         one more argument for every sbatch call, e.g. --sbatch --partition=gpu
  --rerun-failed PARTS submit again only the tasks whose part is missing, and a fresh merge
  SCENE                as for cltrace render (the built-in scene)
  -- FLAGS             more cltrace render flags, the same for every task (--shade path ...)
USAGE
}

die() {
    echo "submit.sh: $*" >&2
    exit 2
}

positive() {
    [[ $2 =~ ^[1-9][0-9]*$ ]] || die "$1 wants a positive whole number, not '$2'"
}

absolute() {
    local dir
    dir=$(cd "$(dirname "$1")" 2>/dev/null && pwd) || die "$1: its folder does not exist"
    echo "$dir/$(basename "$1")"
}

# Submits with sbatch, passes its error on, and prints the job id.
submit() {
    local out
    out=$(sbatch --parsable "${SBATCH_ARGS[@]}" "$@") || {
        echo "submit.sh: sbatch failed: sbatch $*" >&2
        return 1
    }
    echo "${out%%;*}"
}

# Submits the render array for the task ids $1 (Slurm's --array syntax, e.g. 0-3 or 1,3),
# then the merge after it and the failure report, and prints their ids.
submit_jobs() {
    local array=$1 render merge report
    mkdir -p "$PARTS/logs"
    render=$(submit --array="$array" "${GRES[@]}" --job-name=cltrace-render \
        --output="$PARTS/logs/render-%A_%a.out" "$SCRIPTS/render-array.sbatch" "$PARTS") || exit 1
    merge=$(submit --dependency=afterok:"$render" --job-name=cltrace-merge \
        --output="$PARTS/logs/merge-%j.out" "$SCRIPTS/merge.sbatch" "$PARTS") || {
        scancel "$render"
        exit 1
    }
    report=$(submit --dependency=afternotok:"$render" --job-name=cltrace-merge-report \
        --output="$PARTS/logs/merge-%j.out" "$SCRIPTS/merge.sbatch" "$PARTS") || {
        scancel "$render" "$merge"
        exit 1
    }
    printf 'render %s %s\nmerge %s\nreport %s\n' "$render" "$array" "$merge" "$report" >>"$PARTS/jobs"
    echo "render: job $render, tasks $array (logs: $PARTS/logs/render-${render}_<task>.out)"
    echo "merge: job $merge, once every task has succeeded: writes $OUTPUT (log: $PARTS/logs/merge-$merge.out)"
    echo "report: job $report, only if a task fails: names the missing parts (log: $PARTS/logs/merge-$report.out)"
}

# Fails unless job.conf's render jobs have all ended: a task still pending or running
# would write its part twice.
check_ended() {
    local kind id rest active
    while read -r kind id rest; do
        [[ $kind == render ]] || continue
        active=$(squeue -h -j "$id" -o %i 2>/dev/null || true)
        [[ -z $active ]] || die "render job $id has tasks pending or running (${active//$'\n'/ }): wait for them, or scancel $id"
    done <"$PARTS/jobs"
}

rerun_failed() {
    [[ -f $PARTS/job.conf ]] || die "$PARTS/job.conf not found: not a parts folder of submit.sh"
    source "$PARTS/job.conf"
    source "$SCRIPTS/lib.sh"
    # The GPUs asked for at first, unless --sbatch says otherwise.
    GRES=()
    ((GPUS > 0)) && GRES=(--gres=gpu:"$GPUS")
    check_ended
    local missing
    missing=$(missing_tasks)
    if [[ -z $missing ]]; then
        local merge
        merge=$(submit --job-name=cltrace-merge --output="$PARTS/logs/merge-%j.out" \
            "$SCRIPTS/merge.sbatch" "$PARTS") || exit 1
        echo "merge $merge" >>"$PARTS/jobs"
        echo "every part is there: merge: job $merge, writes $OUTPUT (log: $PARTS/logs/merge-$merge.out)"
        return
    fi
    echo "re-running the tasks whose part is missing: $missing"
    submit_jobs "$missing"
}

OUTPUT="" WIDTH="" HEIGHT="" SPP="" TASKS=4 SPLIT=tiles PARTS="" GPUS=0 CLTRACE=cltrace SCENE=""
RERUN=""
FLAGS=() SBATCH_ARGS=()
while (($#)); do
    case $1 in
    -o | --output) OUTPUT=${2:?$1 needs a value}; shift 2 ;;
    --width) WIDTH=${2:?$1 needs a value}; shift 2 ;;
    --height) HEIGHT=${2:?$1 needs a value}; shift 2 ;;
    --spp) SPP=${2:?$1 needs a value}; shift 2 ;;
    --tasks) TASKS=${2:?$1 needs a value}; shift 2 ;;
    --split) SPLIT=${2:?$1 needs a value}; shift 2 ;;
    --parts) PARTS=${2:?$1 needs a value}; shift 2 ;;
    --gpus-per-task) GPUS=${2:?$1 needs a value}; shift 2 ;;
    --cltrace) CLTRACE=${2:?$1 needs a value}; shift 2 ;;
    --sbatch) SBATCH_ARGS+=("${2:?$1 needs a value}"); shift 2 ;;
    --rerun-failed) RERUN=${2:?$1 needs a value}; shift 2 ;;
    -h | --help) usage; exit 0 ;;
    --) shift; FLAGS=("$@"); break ;;
    -*) usage >&2; die "unknown option $1" ;;
    *)
        [[ -z $SCENE ]] || die "one scene only: '$SCENE' and '$1'"
        SCENE=$1
        shift
        ;;
    esac
done

command -v sbatch >/dev/null || die "sbatch not found: this needs a Slurm cluster's client commands"

if [[ -n $RERUN ]]; then
    PARTS=$(absolute "$RERUN")
    rerun_failed
    exit 0
fi

[[ -n $OUTPUT ]] || die "-o IMAGE is required"
[[ -n $WIDTH && -n $HEIGHT ]] || die "--width and --height are required (the tiles are cut from them)"
[[ -n $SPP ]] || die "--spp is required (the sample ranges are cut from it)"
positive --width "$WIDTH"
positive --height "$HEIGHT"
positive --spp "$SPP"
positive --tasks "$TASKS"
[[ $GPUS =~ ^[0-9]+$ ]] || die "--gpus-per-task wants a whole number, not '$GPUS'"
case $SPLIT in
tiles)
    source "$SCRIPTS/lib.sh"
    columns=$(grid_columns)
    ((columns <= WIDTH && TASKS / columns <= HEIGHT)) ||
        die "$TASKS tiles ($columns columns, $((TASKS / columns)) rows) do not fit into ${WIDTH}x$HEIGHT pixels"
    ;;
samples) ((TASKS <= SPP)) || die "$TASKS tasks cannot share $SPP samples per pixel" ;;
*) die "--split is tiles or samples, not '$SPLIT'" ;;
esac
for flag in "${FLAGS[@]}"; do
    case $flag in
    -o | --output* | --region* | --samples* | --width* | --height* | --spp*)
        die "$flag is submit.sh's to set: give it as submit.sh's own option (or leave it out)" ;;
    esac
done

resolved=$(command -v "$CLTRACE") || die "$CLTRACE not found: give the binary with --cltrace PATH"
CLTRACE=$(absolute "$resolved")
OUTPUT=$(absolute "$OUTPUT")
[[ -z $SCENE ]] || { [[ -f $SCENE ]] || die "$SCENE: no such file"; SCENE=$(absolute "$SCENE"); }
PARTS=$(absolute "${PARTS:-$OUTPUT.parts}")
if [[ -e $PARTS/job.conf ]]; then
    die "$PARTS holds an earlier render: remove it, or finish that one with --rerun-failed $PARTS"
fi
mkdir -p "$PARTS/logs"

GRES=()
if ((GPUS > 0)); then
    GRES=(--gres=gpu:"$GPUS")
    # Slurm's CUDA_VISIBLE_DEVICES leaves each task only its own GPUs, so the first GPU is
    # the task's; the user's --device or CLTRACE_DEVICE (passed on to the jobs) wins.
    picked=${CLTRACE_DEVICE:-}
    for flag in "${FLAGS[@]}"; do [[ $flag == --device* ]] && picked=yes; done
    [[ -n $picked ]] || FLAGS+=(--device gpu)
fi

# What the job scripts read (they source it): bash's own quoting of every value.
{
    echo "# Written by submit.sh: the settings of one frame's render tasks and merge."
    for name in SCRIPTS CLTRACE SCENE OUTPUT WIDTH HEIGHT SPP TASKS SPLIT GPUS; do
        printf '%s=%q\n' "$name" "${!name}"
    done
    printf 'FLAGS=('
    ((${#FLAGS[@]} == 0)) || printf '%q ' "${FLAGS[@]}"
    printf ')\n'
} >"$PARTS/job.conf"
: >"$PARTS/jobs"

submit_jobs "0-$((TASKS - 1))"
