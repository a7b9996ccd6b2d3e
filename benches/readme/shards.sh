#!/usr/bin/env bash
# The README's shard timings (cluster section): `cube` 512² × 256 gather rays on one machine,
# then as 4 shards one after another (each as one of 4 machines would run it), each shard's
# seconds from its JSON, and the merge checked byte for byte against the one-machine EXR.
# Usage: benches/readme/shards.sh [HMDIST]   (default: target/release/hmdist)
set -euo pipefail
hmdist="$(realpath "${1:-target/release/hmdist}")"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
cd "$dir"
seconds() { python3 -c "import json,sys; print('%.2f' % json.load(open(sys.argv[1]))['seconds']['total'])" "$1"; }
args=(--size 512x512 --rays 256)
"$hmdist" render --quiet "${args[@]}" --out one.exr
echo "one machine: $(seconds one.json) s"
for k in 0 1 2 3; do
    "$hmdist" render --quiet "${args[@]}" --shard "$k/4" --out "part$k.exr"
    echo "shard $k/4: $(seconds "part$k.json") s"
done
"$hmdist" merge --quiet merged.exr part0.exr part1.exr part2.exr part3.exr
cmp -s merged.exr one.exr && echo "merged = one machine's EXR, byte for byte" || { echo "merged EXR differs"; exit 1; }
