#!/usr/bin/env bash
# The GPU figures (about 2 minutes on an H200): the GPU's name, a smoke render, the GPU
# part of `cargo bench --bench gather` (cube and hall, 1024² × 256 and 4,096), the paper's
# reference (`cube` 1024² × 65,536 rays, --seed 1000003) on the GPU with its f_diff against the
# committed CPU reference, the cube map by rays at 1024² × 4,096 (`--gpu-fill rays`, built
# 2026-12-04 after the H200 rasterised slowly; not yet run on a GPU), and `cargo bench --bench
# cubemap` (64², cpu, gpu raster and gpu rays). README.md beside this has the 2026-12-04 H200
# figures.
#
# On a GPU machine without a Rust toolchain or crates, build elsewhere and copy the binaries,
# and the Vulkan loader where the machine has NVIDIA's driver but no libvulkan.so.1:
#   printf '/.dev/\n/.gl/\n' >> .git/info/exclude; mkdir -p .dev .gl /tmp/amd64/partial
#   cargo build --release && cargo bench --no-run --bench gather --bench cubemap
#   strip -o .dev/hmdist target/release/hmdist      # 76 MB with line tables, 11 MB stripped
#   for b in gather cubemap; do strip -o .dev/$b $(ls -t target/release/deps/$b-* | grep -v '\.d$' | head -1); done
#   o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
#   apt-get $o update && (cd .gl && apt-get $o download libvulkan1)
# then, on the GPU machine, with .dev and .gl beside the checkout:
#   DEVICE=1 docs/paper-scale/gpu-figures.sh 2>&1 | tee $OUT/gpu-figures.log
# It writes reference_gpu.json and reference_gpu_diff.png into OUT. BUDGET (seconds, default
# 400) bounds the whole; the reference is skipped where its first sixteenth projects past it.
# Locally, on lavapipe, as a check of the script: HMDIST_GPU_SOFTWARE=1 SIDE=32 REF_RAYS=64.
set -uo pipefail
cd "$(dirname "$0")/../.."
t0=$(date +%s)
budget=${BUDGET:-400}
side=${SIDE:-1024}
bins=${BIN_DIR:-.dev}
out=${OUT:-/tmp/gpu-figures}
mkdir -p "$out"
left() { echo $((budget - ($(date +%s) - t0))); }
step() { echo; echo "=== [$(($(date +%s) - t0)) s] $*"; }
json() { # FILE: the render's seconds, speed and escaped rays, from its JSON sidecar
    python3 -c "import json,sys;d=json.load(open(sys.argv[1]));s=d['seconds'];print('total', round(s['total'],2), 's, trace', round(s.get('gpu_trace') or 0,3), 's,', round(d['mrays_per_s'],1), 'Mrays/s,', d['escaped_rays'], 'of', d['rays_cast'], 'rays escaped,', d['adapter'])" "$1" 2>&1
}
if [ -n "${DEVICE:-}" ] && [ "$(id -u)" -eq 0 ]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd
bin=$PWD/$bins/hmdist

step "machine"
nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm --format=csv,noheader 2>&1
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs), $(nproc) cores"
"$bin" gpu list 2>&1

step "smoke: cube ${side}² × 256, --backend gpu"
timeout 60 "$bin" render --scene cube --size "${side}x${side}" --rays 256 --sampler grid --backend gpu \
    --out /tmp/smoke.exr --quiet 2>&1
json /tmp/smoke.json

step "cargo bench --bench gather, GPU part"
HMDIST_BENCH_PRESETS= HMDIST_BENCH_GPU_SIZE=$side timeout 120 "$bins/gather" 2>&1

step "the paper's reference on the GPU: its first sixteenth, to time it"
ref=(--scene cube --size "${side}x${side}" --rays "${REF_RAYS:-65536}" --seed 1000003 --bvh high
     --sampler grid --backend gpu --quiet)
timeout 120 "$bin" render "${ref[@]}" --shard 0/16 --out /tmp/ref_s0.exr 2>&1
json /tmp/ref_s0.json
# The build, then 16 times the first part's cast with 30 % to spare.
projected=$(python3 -c "import json;s=json.load(open('/tmp/ref_s0.json'))['seconds'];print(int(s['accel_build']+s['primary']+16*1.3*s['estimate']+1))" 2>/dev/null || echo 99999)
if [ "$projected" -lt $(($(left) - 60)) ]; then
    step "the whole reference (projected $projected s)"
    timeout $(($(left) - 60)) "$bin" render "${ref[@]}" --out "$out/reference_gpu.exr" 2>&1
    json "$out/reference_gpu.json"
    [ "$side" = 1024 ] && [ -f "$out/reference_gpu.exr" ] &&
        "$bin" diff docs/paper-scale/cube/reference.exr "$out/reference_gpu.exr" \
            --png "$out/reference_gpu_diff.png" 2>&1
    rm -f "$out/reference_gpu.exr" "$out/reference_gpu.png" # 4 MB; the JSON and diff say it
else
    echo "skipped the whole reference: projected $projected s, $(left) s left"
fi

step "cube map by rays (--gpu-fill rays): cube ${side}² × 4,096, R = 64"
timeout 120 "$bin" render --method cubemap --scene cube --size "${side}x${side}" --rays 4096 --cube-res 64 \
    --backend gpu --gpu-fill rays --out /tmp/cubemap_rays.exr --quiet 2>&1
json /tmp/cubemap_rays.json

step "cargo bench --bench cubemap (${CUBE_SIDE:-64}², R = 64; cpu, gpu raster and gpu rays)"
HMDIST_BENCH_SIZE=${CUBE_SIDE:-64} timeout $(($(left) > 10 ? $(left) : 10)) "$bins/cubemap" 2>&1
step "done"
