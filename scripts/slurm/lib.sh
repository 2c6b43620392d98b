# Shared by submit.sh and the job scripts (sourced, after the parts folder's job.conf, which
# submit.sh writes): where each task's part goes, which parts are missing, and what a task
# renders.

# The finished part of task $1. Tasks write under a hidden temporary name and rename, so a
# part that is there is whole.
part_of() { printf '%s/part-%s.exr' "$PARTS" "$1"; }

# The ids of the tasks whose part is missing, comma-separated (Slurm's --array syntax), or
# nothing when every part is there.
missing_tasks() {
    local id absent=()
    for ((id = 0; id < TASKS; id++)); do
        [[ -f $(part_of "$id") ]] || absent+=("$id")
    done
    local IFS=,
    echo "${absent[*]}"
}

# The tile grid of $TASKS tiles: as many columns as the largest divisor of TASKS that is at
# most its square root, the rest as rows (4: 2x2, 6: 2 columns of 3 rows, 5: 5 bands).
grid_columns() {
    local d columns=1
    for ((d = 1; d * d <= TASKS; d++)); do
        ((TASKS % d == 0)) && columns=$d
    done
    echo "$columns"
}

# The cltrace render flags of task $1: its tile (--region X0,Y0,X1,Y1, with all --spp
# samples) or its share of the samples (--samples A..B, which stands for --spp); ends
# exclusive, shares as even as integers allow.
task_flags() {
    local id=$1
    if [[ $SPLIT == tiles ]]; then
        local columns rows column row
        columns=$(grid_columns)
        rows=$((TASKS / columns))
        column=$((id % columns))
        row=$((id / columns))
        echo "--region $((column * WIDTH / columns)),$((row * HEIGHT / rows)),$(((column + 1) * WIDTH / columns)),$(((row + 1) * HEIGHT / rows)) --spp $SPP"
    else
        echo "--samples $((id * SPP / TASKS))..$(((id + 1) * SPP / TASKS))"
    fi
}

# The newest log of task $1, if any.
task_log() {
    local log
    # shellcheck disable=SC2012 # the names are render-<job id>_<task id>.out
    log=$(ls -t "$PARTS"/logs/render-*_"$1".out 2>/dev/null | head -n 1) || true
    echo "$log"
}
