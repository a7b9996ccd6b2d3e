#!/usr/bin/env bash
# Fig. 9 taken apart at a size that fits a session: what each difference between the cube
# map and final gathering measures, at 65,536 rays on `cube` (the paper's scene A).
#
#   docs/paper-scale/fig9-anatomy/run.sh [SIZE [OUT [BACKENDS]]]   # default 128, /tmp/fig9-anatomy, "cpu gpu-software"
#
# Renders (seed 1 unless said; 65,536 rays; each image's JSON beside it):
#   ref        gather, seed 1000003: the experiments' reference
#   gather     gather, seed 1: an independent second reference
#   cube-BACKEND-rR   the cube map at R = 64 and 128 on each backend (cpu: a ray through each
#              looked-up texel centre; gpu-software: rasterised hemicubes on lavapipe, gpu: on
#              a hardware GPU), with seed 1's directions: gather's own
# then prints every pair's f_diff (hmdist diff) as CSV on stdout:
#   gather vs ref         the noise floor: two independent 65,536-ray images
#   cube-cpu vs gather    the texels' quantisation alone (the same directions, the same rays'
#                         targets up to the texel centre)
#   cube-X vs cube-cpu    what rasterising adds (depth precision, coverage) over the ray
#                         through the texel centre
#   cube-X vs ref         what the paper's Fig. 9 measures (its CPU gather against its cube map)
set -euo pipefail
size="${1:-128}"
out="${2:-/tmp/fig9-anatomy}"
backends="${3:-cpu gpu-software}"
hmdist="${HMDIST:-target/release/hmdist}"
mkdir -p "$out"
render() { # NAME ARGS...
    local name="$1"
    shift
    if [ ! -f "$out/$name.json" ]; then
        local start=$SECONDS
        "$hmdist" render --scene cube --size "${size}x${size}" --rays 65536 --sampler grid --quiet \
            --out "$out/$name.exr" "$@" >&2
        echo "$name: $((SECONDS - start)) s" >&2
    fi
}
render ref --seed 1000003 --backend cpu
render gather --seed 1 --backend cpu
for backend in $backends; do
    for r in 64 128; do
        render "cube-$backend-r$r" --method cubemap --cube-res "$r" --seed 1 --backend "$backend"
    done
done
f_diff() { "$hmdist" diff "$out/$1.exr" "$out/$2.exr" | awk '/^f_diff:/ {print $2}'; }
echo "image,against,measures,f_diff"
echo "gather,ref,noise floor (two independent 65536-ray images),$(f_diff ref gather)"
for backend in $backends; do
    for r in 64 128; do
        name="cube-$backend-r$r"
        [ "$backend" = cpu ] && echo "$name,gather,quantisation alone (same directions),$(f_diff gather "$name")"
        [ "$backend" != cpu ] && echo "$name,cube-cpu-r$r,rasterisation over the texel-centre ray,$(f_diff "cube-cpu-r$r" "$name")"
        echo "$name,ref,the paper's Fig. 9 comparison,$(f_diff ref "$name")"
    done
done
