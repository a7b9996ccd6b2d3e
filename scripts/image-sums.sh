#!/usr/bin/env bash
# Renders every method and backend this machine can run on `cube` and `hall`,
# small, and prints one sha256 per EXR: run it before and after a refactor
# that must not change images (issue #23), and diff the two listings.
#   scripts/image-sums.sh [HMDIST_BINARY] > sums.txt
# (It spells K --gather, the older name of --nearest, so that it runs on older builds too; it
# names --sampler grid, the default before sobol, so that its sums compare across that change.)
set -euo pipefail
bin=${1:-target/release/hmdist}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export HMDIST_GPU_SOFTWARE=1
render() { # name, then render flags
    local name=$1; shift
    "$bin" render --quiet --size 40x40 --out "$tmp/$name.exr" "$@"
    echo "$(sha256sum < "$tmp/$name.exr" | cut -c1-16)  $name"
}
for scene in cube hall; do
    for backend in cpu gpu-software; do
        render "$scene-gather-$backend" --scene "$scene" --method gather --rays 64 --sampler grid --backend "$backend"
        render "$scene-cubemap-$backend" --scene "$scene" --method cubemap --rays 64 --cube-res 16 --backend "$backend"
    done
    render "$scene-gather-aov" --scene "$scene" --method gather --rays 64 --sampler grid --backend cpu \
        --aov relerr,rays,dmin,ao,escaped --ao-radius 1
    render "$scene-gather-fast" --scene "$scene" --method gather --rays 64 --sampler grid --backend cpu --bvh fast
    render "$scene-gather-sobol" --scene "$scene" --method gather --rays 64 --backend cpu --sampler sobol --rounds 2
    render "$scene-gather-clamp" --scene "$scene" --method gather --rays 32 --sampler grid --backend cpu --max-distance 2 --seed 7
    render "$scene-adaptive" --scene "$scene" --method adaptive --min-rays 16 --max-rays 256 \
        --sampler grid --aov rays,relerr
    render "$scene-adaptive-sobol" --scene "$scene" --method adaptive --min-rays 16 --max-rays 256 \
        --sampler sobol --loosen 0.5 --aov rays
    render "$scene-photon1" --scene "$scene" --method photon1 --photons 20000 --gather 32
    render "$scene-photon2" --scene "$scene" --method photon2 --photons 20000 --gather 32 --source camera
done
