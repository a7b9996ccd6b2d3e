#!/usr/bin/env bash
# One device call: GPU gather bench, the paper reference on the GPU (against the committed CPU
# reference), the cube-map bench, then docs/paper-scale/gpu.sh for what time is left.
# BUDGET seconds in all. Locally (lavapipe): HMDIST_GPU_SOFTWARE=1 SIDE=64 BUDGET=120.
set -uo pipefail
t0=$(date +%s)
budget=${BUDGET:-570}
side=${SIDE:-1024}
out=${OUT:-/tmp/devout}; mkdir -p "$out"
left() { echo $((budget - ($(date +%s) - t0))); }
step() { echo; echo "=== [$(( $(date +%s) - t0 )) s] $*"; }
if ls .gl/*.deb >/dev/null 2>&1 && [ "$(id -u)" -eq 0 ] && [ -n "${DEVICE:-}" ]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd \
    __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
bin=$PWD/.dev/hmdist
step "machine"
nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm --format=csv,noheader 2>&1
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs), $(nproc) cores"
"$bin" gpu list 2>&1
step "smoke: cube ${side}² x 256, --backend gpu"
timeout 60 "$bin" render --scene cube --size ${side}x${side} --rays 256 --backend gpu \
    --out /tmp/smoke.exr --quiet 2>&1
python3 -c "import json;d=json.load(open('/tmp/smoke.json'));print('smoke', d['seconds'], d['mrays_per_s'], 'Mrays/s', d['escaped_rays'], 'escaped', d['adapter'])" 2>&1

step "gather bench, GPU part (1024² x 256 and 4,096 on cube and hall)"
HMDIST_BENCH_PRESETS= HMDIST_BENCH_GPU_SIZE=$side timeout 120 .dev/gather 2>&1

step "the paper's reference on the GPU: part 0 of 16 first, to time it"
ref=(--scene cube --size ${side}x${side} --rays ${REF_RAYS:-65536} --seed 1000003 --bvh high --backend gpu --quiet)
timeout 120 "$bin" render "${ref[@]}" --shard 0/16 --out /tmp/ref_s0.exr 2>&1
s0=$(python3 -c "import json;d=json.load(open('/tmp/ref_s0.json'));s=d['seconds'];print(int(s['accel_build']+s['primary']+16*1.3*s['estimate']+1))" 2>/dev/null || echo 9999)
echo "whole projected: ${s0} s; part 0: $(python3 -c "import json;d=json.load(open('/tmp/ref_s0.json'));print(d['seconds'], d['mrays_per_s'], 'Mrays/s', d['escaped_rays'], 'escaped')" 2>&1)"
# Projected: the build, then 16 parts of part 0's cast with 30 % to spare.
if [ $s0 -lt $(( $(left) - 200 )) ]; then
    step "whole reference on the GPU (budget $(( $(left) - 200 )) s)"
    timeout $(( $(left) - 200 )) "$bin" render "${ref[@]}" --out "$out/reference_gpu.exr" 2>&1
    [ -f "$out/reference_gpu.exr" ] && "$bin" diff docs/paper-scale/cube/reference.exr "$out/reference_gpu.exr" \
        --png "$out/reference_gpu_diff.png" 2>&1
    rm -f "$out/reference_gpu.exr"   # 4 MB; the JSON and the diff say what matters
else
    echo "skipped the whole reference: projected ${s0} s, $(left) s left"
fi

step "cube-map bench (64², R = 64, N = 256 / 4,096 / 16,384; cpu and gpu)"
HMDIST_BENCH_SIZE=${CUBE_SIDE:-64} timeout 90 .dev/cubemap 2>&1

lim=$(( $(left) - 45 ))
step "docs/paper-scale/gpu.sh, LIMIT=$lim"
if [ "$lim" -gt 60 ]; then
    LIMIT=$lim HMDIST_BIN=$bin timeout $((lim + 20)) docs/paper-scale/gpu.sh /tmp/paper-cube 2>&1
    ls -la /tmp/paper-cube /tmp/paper-cube/cache 2>&1 | head -60
    (cd /tmp && tar czf "$out/paper-cube.tgz" --exclude='*.exr' paper-cube 2>&1; ls -la "$out/paper-cube.tgz")
else
    echo "no time left for it"
fi
step "done"
