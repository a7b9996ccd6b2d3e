#!/usr/bin/env bash
# Second call: edge-function fix on NVIDIA. Old vs new binary on cube 1024² x 4,096, then the
# whole reference with the new one.
set -uo pipefail
out=${OUT:-/tmp/devout}; mkdir -p "$out"; t0=$(date +%s)
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd
show() { python3 -c "import json,sys;d=json.load(open(sys.argv[1]));s=d['seconds'];print(sys.argv[2], 'total', round(s['total'],2), 'trace', round(s['gpu_trace'],3), 'Mrays/s', round(d['mrays_per_s'],1), 'escaped', d['escaped_rays'], 'of', d['rays_cast'])" "$@"; }
for rays in 256 4096; do
  for b in hmdist_old hmdist; do
    timeout 40 .dev/$b render --scene cube --size 1024x1024 --rays $rays --backend gpu --out /tmp/$b-$rays.exr --quiet 2>&1
    show /tmp/$b-$rays.json "$b N=$rays"
  done
  .dev/hmdist diff /tmp/hmdist_old-$rays.exr /tmp/hmdist-$rays.exr 2>&1 | head -3
done
timeout 40 .dev/hmdist render --scene hall --size 1024x1024 --rays 4096 --backend gpu --out /tmp/hall.exr --quiet 2>&1; show /tmp/hall.json "new hall N=4096"
echo "[$(( $(date +%s) - t0 )) s] whole reference, new shader"
timeout 130 .dev/hmdist render --scene cube --size 1024x1024 --rays 65536 --seed 1000003 --bvh high --backend gpu --out "$out/reference_gpu.exr" --quiet 2>&1
show "$out/reference_gpu.json" "reference"
.dev/hmdist diff docs/paper-scale/cube/reference.exr "$out/reference_gpu.exr" --png "$out/reference_gpu_diff.png" 2>&1
rm -f "$out/reference_gpu.exr" "$out/reference_gpu.png"
echo "[$(( $(date +%s) - t0 )) s] done"
