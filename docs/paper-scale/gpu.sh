#!/usr/bin/env bash
# The paper's `cube` reproduction at its own scale on a GPU machine: gather and the
# cube map on the GPU, the photon studies on the CPU side. Prints the GPU's name, the plan
# (every image, each once, with its estimated seconds), then each experiment's seconds, and
# writes the tables, plots, picture grids and index.html into OUT.
#
#   docs/paper-scale/gpu.sh [OUT]        # default: $OUT/paper-cube on the device machine,
#                                        # else /tmp/paper-cube
#
# Run time: on an H200 (2026-12-04) the GPU cube map rasterised about 1,900 hemicubes/s, about
# 9 minutes per 1024² pass, and the plan's calibration took longer than its 120 s (README.md
# beside this, "First run"). Since then the cube maps are filled by rays (GPU_FILL, below),
# which should take them to seconds; the photon studies take about 12 minutes of 16 cores.
# gpu-figures.sh makes the GPU figures alone, in about 2 minutes.
# The run stops cleanly after LIMIT seconds (default 420) and keeps the images it finished in
# OUT/cache (large ones in parts), so running the script again continues where it stopped;
# the run that finishes writes the report, and each experiment's planned and actual seconds
# (OUT/plan_vs_actual.md: the seconds of every call since the plan). HMDIST_BIN names a
# prebuilt binary (the device machine may have no Rust toolchain or crates); otherwise the
# script builds one.
set -uo pipefail
cd "$(dirname "$0")/../.."
out="${1:-${OUT:-/tmp}/paper-cube}"
limit="${LIMIT:-420}"
bin="${HMDIST_BIN:-target/release/hmdist}"
if [ ! -x "$bin" ]; then
    cargo build --release -q || exit 2
fi
echo "GPU: $(nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null || echo none found)"
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs), $(nproc) cores"
echo "hmdist: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
# The committed CPU reference (1024² × 65,536 rays) is every f_diff's reference, as the CPU
# run's: the GPU's images are measured against CPU final gathering, as in the paper's Fig. 9.
# GPU_FILL: how the cube maps fill their texels on the GPU. rays (the default here) casts a
# ray per looked-up texel, at the gather's speed; raster is the paper's method, about 9
# minutes per 1024² pass on an H200 (2026-12-04).
common=(--scene cube --preset paper --backend gpu --gpu-fill "${GPU_FILL:-rays}" --out "$out" --quiet
        --reference docs/paper-scale/cube/reference.exr)

# The plan first: a calibration of a few rows of every image (a few percent of the run). Only
# on the first call: a later one continues that run, and its plan against the run counts the
# images the earlier calls rendered (a new plan would find them cached and count them as free).
start=$(date +%s)
if [ -f "$out/plan.json" ]; then
    echo "plan: $out/plan.md (made by the first call; remove $out/plan.json to plan again)"
else
    # PLAN_LIMIT: the calibration's seconds (on the H200 it outran 120, mostly in the photon
    # images, each of which builds its whole photon map).
    timeout -s INT "${PLAN_LIMIT:-120}" "$bin" experiment all "${common[@]}" --plan && sed -n 1,16p "$out/plan.md"
fi
left=$((limit - ($(date +%s) - start)))
timeout -s INT "$left" "$bin" experiment all "${common[@]}"
status=$?
echo "wall: $(($(date +%s) - start)) s"
if [ "$status" -eq 0 ]; then
    cat "$out/plan_vs_actual.md"
    echo "report: $out/index.html"
else
    echo "stopped (status $status) after the images in $out/cache: run the script again to continue"
    exit 1
fi
