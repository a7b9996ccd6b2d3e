#!/usr/bin/env bash
# Renders an HMD image on a Slurm cluster: an array of M shards, then a merge job that runs
# once every shard has succeeded (--dependency=afterok). The merged EXR is byte for byte the
# one `hmdist render` makes on one machine with the same options.
#   usage: render.sh M PARTS_DIR OUT.exr [hmdist render options...]
#   e.g.   render.sh 16 parts hmd.exr --scene hall --rays 65536 --size 1024x1024
# HMDIST names the binary (default: hmdist on PATH); HMDIST_SLURM_WAIT=1 waits for both jobs
# (sbatch --wait) and fails if either fails. Extra sbatch options go in SBATCH_* variables.
# HMDIST_SLURM_GPUS=N asks each shard for N GPUs (--gres=gpu:N); Slurm then sets each task's
# CUDA_VISIBLE_DEVICES, which hmdist follows to pick its adapter (use with --backend gpu|auto).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
m=${1:?the number of shards}; parts=${2:?a folder for the parts}; out=${3:?the merged EXR}
shift 3
wait=() gres=()
[ -n "${HMDIST_SLURM_WAIT:-}" ] && wait=(--wait)
[ -n "${HMDIST_SLURM_GPUS:-}" ] && gres=(--gres="gpu:$HMDIST_SLURM_GPUS")
array=$(sbatch --parsable "${wait[@]}" "${gres[@]}" --array="0-$((m - 1))" "$here/render.sbatch" "$parts" "$@")
echo "shards: job $array (array 0-$((m - 1)))"
merge=$(sbatch --parsable "${wait[@]}" --dependency="afterok:${array%%;*}" "$here/merge.sbatch" "$parts" "$out")
echo "merge: job $merge -> $out"
