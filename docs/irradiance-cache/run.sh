#!/usr/bin/env bash
# The irradiance-cache experiment (docs/irradiance-cache/README.md): on `cube` and `hall`, an
# irradiance cache of each spacing source at each accuracy a, against a brute-force image of E
# made with another seed; then analyse.py writes the tables and plots.
#
#   docs/irradiance-cache/run.sh [BIN] [RUNS]     (BIN: target/release/hmdist; RUNS: a folder)
#
# SIZE (256x256), M (the records' rays, 512) and REF_RAYS (the references' rays, 4096) may be
# set in the environment. A run already in RUNS is kept: the script goes on where it stopped.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-target/release/hmdist}
RUNS=${2:-target/irradiance-cache}
SIZE=${SIZE:-256x256}
M=${M:-512}
REF_RAYS=${REF_RAYS:-4096}
ACCURACIES=${ACCURACIES:-0.05 0.1 0.15 0.2 0.3 0.4}

# name, spacing, extra flags: the sources of H, and the renderers' rules with their clamps.
SOURCES=$(cat <<'LIST'
hmd           hmd
oracle        oracle                                   --oracle=H_REF
gather64      hmd:gather:rays=64,backend=cpu
cubemap       hmd:cubemap:cube_res=16,rays=256,backend=cpu
photon1       hmd:photon1:photons=200000,nearest=64
photon2       hmd:photon2:photons=200000,nearest=64
pbrt-v2       min                                      --clamp-pixels=2.5,15
mitsuba       min10                                    --clamp-pixels=3,20 --clamp-scene=0.005,0.32
hmd-clamped   hmd                                      --clamp-pixels=3,20 --clamp-scene=0.005,0.32
LIST
)

for scene in cube hall; do
    dir="$RUNS/$scene"
    mkdir -p "$dir"
    # The references: E by brute force, and H for the oracle. A second E with another seed,
    # measured against the first (a cache of a = 1e-9 is the brute-force image), is the
    # references' own noise: the floor under every error below.
    [ -f "$dir/e-ref-7.json" ] || "$BIN" render --quiet --method irradiance --scene "$scene" \
        --size "$SIZE" --rays "$REF_RAYS" --seed 7 --out "$dir/e-ref-7.exr"
    [ -f "$dir/noise.json" ] || "$BIN" cache --quiet --scene "$scene" --size "$SIZE" --rays "$REF_RAYS" \
        --seed 8 --accuracy 1e-9 --reference "$dir/e-ref-7.exr" --out "$dir/noise.exr"
    [ -f "$dir/h-ref.json" ] || "$BIN" render --quiet --scene "$scene" --size "$SIZE" --rays 4096 \
        --backend cpu --seed 7 --out "$dir/h-ref.exr"
    while read -r name spacing extra; do
        [ -n "$name" ] || continue
        for a in $ACCURACIES; do
            out="$dir/$name-a$a.exr"
            [ -f "${out%.exr}.json" ] && continue
            # shellcheck disable=SC2086
            "$BIN" cache --quiet --scene "$scene" --size "$SIZE" --rays "$M" --accuracy "$a" \
                --spacing "$spacing" ${extra//H_REF/$dir/h-ref.exr} --reference "$dir/e-ref-7.exr" \
                --diff-png "${out%.exr}-error.png" --out "$out"
            echo "$scene $name a=$a: $(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print(r["records"], "records,", round(100*r["reference"]["mean_relative_error"],2), "% mean error,", round(r["seconds"]["total"],1), "s")' "${out%.exr}.json")"
        done
    done <<< "$SOURCES"
done
python3 docs/irradiance-cache/analyse.py "$RUNS" docs/irradiance-cache
