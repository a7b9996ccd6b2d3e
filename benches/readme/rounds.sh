#!/usr/bin/env bash
# The README's "rounds cost accuracy" figures (AOVs section): f_diff of 256 gather rays per
# pixel on a 48² `cube`, as one stratified grid and as 8 and 32 independent rounds (what
# --rounds does to get error bars), against a 16,384-ray reference; with each sampler (the
# grid's rounds are independent grids, sobol's independently scrambled sequences).
# Usage: benches/readme/rounds.sh [HMDIST]   (default: target/release/hmdist)
set -euo pipefail
hmdist="$(realpath "${1:-target/release/hmdist}")"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
cd "$dir"
"$hmdist" render --quiet --size 48x48 --rays 16384 --sampler grid --out reference.exr
for sampler in grid sobol; do
    for rounds in 1 8 32; do
        "$hmdist" render --quiet --size 48x48 --rays 256 --rounds "$rounds" --sampler "$sampler" \
            --out "r$rounds.exr"
        f=$("$hmdist" diff reference.exr "r$rounds.exr" | awk '/^f_diff:/ {print $2}')
        echo "$sampler, 256 rays in $rounds round(s): f_diff $f"
    done
done
