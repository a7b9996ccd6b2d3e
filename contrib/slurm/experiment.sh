#!/usr/bin/env bash
# Runs an hmdist experiment (e.g. the paper preset) on a Slurm cluster: an array of M tasks,
# each rendering its share of the images into OUT/cache (`experiment --shard K/M`), then a job
# that runs once all have succeeded and writes the tables and the report from the cache.
#   usage: experiment.sh M NAME OUT [hmdist experiment options...]
#   e.g.   experiment.sh 32 all paper-cube --preset paper --scene cube
# HMDIST names the binary (default: hmdist on PATH); HMDIST_SLURM_WAIT=1 waits for both jobs.
# HMDIST_SLURM_GPUS=N asks each shard for N GPUs (--gres=gpu:N); Slurm then sets each task's
# CUDA_VISIBLE_DEVICES, which hmdist follows to pick its adapter.
set -euo pipefail
m=${1:?the number of shards}; name=${2:?the experiment}; out=${3:?the output folder}
shift 3
hmdist=${HMDIST:-hmdist}
wait=() gres=()
[ -n "${HMDIST_SLURM_WAIT:-}" ] && wait=(--wait)
[ -n "${HMDIST_SLURM_GPUS:-}" ] && gres=(--gres="gpu:$HMDIST_SLURM_GPUS")
q=$(printf '%q ' "$@")
array=$(sbatch --parsable "${wait[@]}" "${gres[@]}" --job-name=hmdist-experiment --array="0-$((m - 1))" \
    --output="hmdist-experiment-%A_%a.out" \
    --wrap="exec $(printf '%q' "$hmdist") experiment $(printf '%q' "$name") --quiet --out $(printf '%q' "$out") $q --shard \$SLURM_ARRAY_TASK_ID/\$SLURM_ARRAY_TASK_COUNT")
echo "shards: job $array (array 0-$((m - 1)))"
report=$(sbatch --parsable "${wait[@]}" --job-name=hmdist-report --dependency="afterok:${array%%;*}" \
    --output="hmdist-report-%j.out" \
    --wrap="exec $(printf '%q' "$hmdist") experiment $(printf '%q' "$name") --out $(printf '%q' "$out") $q")
echo "report: job $report -> $out/index.html"
