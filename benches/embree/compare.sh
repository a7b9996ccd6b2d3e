#!/usr/bin/env bash
# hmdist against Embree on the same rays: Embree 3 from C (Debian's libembree-dev, robust and
# fast variants) and Embree 4 through Open3D (open3d-cpu from PyPI). Sets the peers up itself
# (run as root on Debian/Ubuntu, or with the packages already installed).
#
#   benches/embree/compare.sh [CASES] [RUNS]                 # pure casting
#   benches/embree/compare.sh --end-to-end [CASES] [RUNS]    # the whole gather
#   benches/embree/compare.sh --accuracy [SCENES] [SIDE] [RUNS]   # seconds to an f_diff
#
# CASES: space-separated SCENE:SIDE:N (default "cube:256:256 cube:64:4096 hall:256:256
# sphere5m:256:64"; end to end: "cube:256:256 cube:64:4096 hall:256:256"); SCENE is a
# built-in, a file hmdist reads, or sphere5m (a closed icosphere of 5,242,880 triangles seen
# from inside, written as OBJ + TOML); SIDE² pixels × N cosine gather rays of `hmdist render`.
#
# Pure casting: each case writes the rays once (origins, the triangle they leave,
# directions), exports hmdist's exact triangles as OBJ, then runs every caster RUNS times
# (default 5), interleaved, on all cores, and prints medians: build seconds, trace Mrays/s,
# escaped rays, hmdist's throughput as a ratio to each peer's, and build + trace seconds
# with the peer's total as a ratio to hmdist's (above 1: hmdist finishes first). Only the BVH
# build and the casting loop are timed, for every caster (hmdist casts as `render` does:
# packets of 4 × 2 neighbouring strata).
#
# End to end: what a user's stopwatch sees of the gather. `hmdist render --method gather`
# (its `seconds.estimate`: directions, casting and sums, after the primary rays) against
# embree_gather.c, which takes the same gather points (origin and normal per pixel), makes
# the same stratified cosine directions with the same random numbers and frame, casts them
# (in the loop or batched: EMBREE_CASTS below) and sums 1/t per pixel, timed as a whole
# (the batched variants' generation also apart, gen_s). Medians of RUNS interleaved runs;
# ratio above 1: hmdist is faster; the summary's last lines compare against the fastest
# Embree variant of each build. Timings drift ±10 %: compare within one run.
#
# Accuracy: the seconds each side needs for an image of a given f_diff, what a user waits
# for. SCENES default "cube hall columns" (columns: benches/scenes/columns.py, a closed
# room), SIDE² pixels (default 256). Per scene one shared reference (`hmdist render --rays
# 8192`, its own seed); then for N = 16 … 2,048 rays, RUNS times (default 3), interleaved:
# Embree (embree_gather.c: hmdist's jittered grid of strata, what a hand-written gather
# casts; the fast build, each EMBREE_CASTS variant, default "4 8 16", the fastest end to
# end; the fastest variant's median seconds); Embree + Intel Open Image Denoise
# (oidn_filter.py on Embree's 1/t, normals as the guide: Embree's seconds and the filter's);
# hmdist with its defaults (`render --rays N`, sobol) and with `--denoise` (the filter's
# seconds added); then hmdist's adaptive gathering (the stop that gives the least f_diff per
# ray: `--tolerance 0 --abs-tolerance A --loosen 1`, A = 0.004 … 0.00025), and adaptive
# with a relative stop and the filter (`--tolerance T --loosen 0.5 --min-rays 64 --denoise`,
# T = 0.2 … 0.02). Seconds are the
# gather's (Embree's gather_s, hmdist's seconds.estimate), after the BVH and the primary
# hits, which each pays once. Each image's f_diff, signed bias, f_diff over the creases (the
# tenth of the pixels with the smallest reference H) and over the rest, and p95 of |ΔH|/H
# (`hmdist diff`). For T = Embree's f_diff at 64, 256 and 1,024 rays: each side's seconds to
# f_diff ≤ T (log-log between the points measured) as a fraction of Embree's, and its p95
# there against Embree's. The pictures of each scene (reference, Embree at 256 rays, hmdist
# at 64 with --denoise, and their differences) go to $HMDIST_COMPARE_PICTURES (default: the
# work folder) as SCENE-denoise.png.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
mode=cast
if [ "${1:-}" = --end-to-end ]; then
    mode=e2e
    shift
elif [ "${1:-}" = --accuracy ]; then
    mode=accuracy
    shift
fi
root="$(cd "$here/../.." && pwd)"
if [ "$mode" = e2e ]; then
    cases="${1:-cube:256:256 cube:64:4096 hall:256:256}"
elif [ "$mode" = accuracy ]; then
    cases="${1:-cube hall columns}"
    shift || true
else
    cases="${1:-cube:256:256 cube:64:4096 hall:256:256 sphere5m:256:64}"
fi
if [ "$mode" = accuracy ]; then
    side="${1:-256}"
    runs="${2:-3}"
else
    runs="${2:-5}"
fi
# End to end: how embree_gather casts (EMBREE_CASTS): `loop` makes each ray inside the cast
# loop; the others make every ray first on all threads, then cast them one at a time (1), as
# packets (4, 8, 16) or as streams (stream). Every variant runs with the robust and the fast
# build; the summary names the fastest of each build.
casts="${EMBREE_CASTS:-loop 1 4 8 16 stream}"
[ "$mode" = accuracy ] && casts="${EMBREE_CASTS:-4 8 16}"
threads="$(nproc)"
work="${HMDIST_COMPARE_DIR:-$(mktemp -d)}"
mkdir -p "$work"

# The peers.
if [ ! -f /usr/include/embree3/rtcore.h ] || ! ldconfig -p | grep -q libusb-1.0; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq libembree-dev libusb-1.0-0 gcc >/dev/null
fi
gcc -O3 -march=native -o "$work/embree_cast" "$here/embree_cast.c" -lembree3 -lpthread -lm
gcc -O3 -march=native -o "$work/embree_gather" "$here/embree_gather.c" -lembree3 -lpthread -lm
venv="${HMDIST_COMPARE_VENV:-$work/venv}"
if [ "$mode" = cast ] && { [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import open3d' 2>/dev/null; }; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install -q open3d-cpu numpy
fi
if [ "$mode" = accuracy ] && { [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import pyoidn, OpenEXR, PIL' 2>/dev/null; }; then
    [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
    "$venv/bin/pip" install -q pyoidn numpy OpenEXR pillow
fi
(cd "$root" && cargo build --release -q --example gather_rays --bin hmdist)
hmdist="$root/target/release/hmdist"
gather_rays="$root/target/release/examples/gather_rays"

if [ "$mode" = accuracy ]; then
    # f_diff, bias, creases, rest and p95 of TEST against REF, as log fields.
    metrics() { # REF TEST SCENE
        "$hmdist" diff "$1" "$2" --scene "$3" | awk -F': *' '
            $1 == "f_diff" { f = $2 } $1 == "bias" { b = $2 } $1 == "f_diff, creases" { c = $2 }
            $1 == "f_diff, the rest" { r = $2 } $1 == "p95 relative error" { p = $2 }
            END { print "f_diff", f, "bias", b, "creases", c, "rest", r, "p95", p }'
    }
    # One hmdist image of the scene into the log as NAME: its rays per pixel (the mean, for
    # adaptive), its gather seconds (with the filter's, if denoised) and, in the first run,
    # its errors. KEEP names a copy of the image to keep.
    hmdist_point() { # NAME KEEP RENDER-FLAGS...
        local name="$1" keep="$2" n seconds error=""
        shift 2
        "$hmdist" render --quiet --scene "$scene" --size "${side}x$side" --threads "$threads" "$@" \
            --out "$work/h.exr" --json "$work/h.json" >/dev/null
        read -r n seconds < <(python3 -c 'import json, sys; d = json.load(open(sys.argv[1]))
print(round(d.get("mean_rays_per_pixel") or d["rays"]), d["seconds"]["estimate"] + (d.get("denoise") or {}).get("seconds", 0))' "$work/h.json")
        [ "$run" = 1 ] && error="$(metrics "$reference" "$work/h.exr" "$scene")"
        [ -n "$keep" ] && cp "$work/h.exr" "$work/$keep"
        echo "$name n $n gather_s $seconds $error" >>"$log"
    }
    pictures="${HMDIST_COMPARE_PICTURES:-$work}"
    mkdir -p "$pictures"
    for scene in $cases; do
        name="$(basename "$scene")"
        if [ "$scene" = columns ]; then
            scene="$(python3 "$here/../scenes/columns.py" "$work/columns")"
        fi
        points="$work/$name-$side.hmdp"
        obj="$work/$name.obj"
        reference="$work/$name-$side-reference.exr"
        [ -f "$points" ] || "$gather_rays" points "$scene" "$side" "$points"
        [ -f "$obj" ] || "$hmdist" scene export "$scene" "$obj" >/dev/null
        [ -f "$reference" ] || "$hmdist" render --quiet --scene "$scene" --size "${side}x$side" \
            --rays 8192 --seed 1000003 --out "$reference" >/dev/null
        log="$work/$name-$side-accuracy.log"
        : >"$log"
        for run in $(seq "$runs"); do
            for n in 16 32 64 128 256 512 1024 2048; do
                keep=""
                [ "$n" = 64 ] && keep="denoise-64.exr"
                hmdist_point hmdist_gather "" --rays "$n"
                hmdist_point hmdist_denoise "$keep" --rays "$n" --denoise
                for cast in $casts; do
                    EMBREE_HMD_OUT="$work/e.f32" "$work/embree_gather" "$obj" "$points" "$n" "$threads" fast "$cast" |
                        awk -v n="$n" '{ $1 = $1 " n " n; print }' >>"$log"
                done
                "$venv/bin/python" "$here/oidn_filter.py" "$points" "$side" "$work/e.f32" "$work/o.f32" |
                    awk -v n="$n" '{ print "oidn n " n " " $0 }' >>"$log"
                if [ "$run" = 1 ]; then
                    "$gather_rays" exr "$side" "$points" "$work/e.f32" "$work/e.exr"
                    "$gather_rays" exr "$side" "$points" "$work/o.f32" "$work/o.exr"
                    echo "embree n $n $(metrics "$reference" "$work/e.exr" "$scene")" >>"$log"
                    echo "embree_oidn n $n $(metrics "$reference" "$work/o.exr" "$scene")" >>"$log"
                    [ "$n" = 256 ] && cp "$work/e.exr" "$work/embree-256.exr"
                fi
            done
            for a in 0.004 0.002 0.001 0.0005 0.00025; do
                hmdist_point hmdist_adaptive "" --method adaptive --tolerance 0 --abs-tolerance "$a" \
                    --loosen 1 --min-rays 64 --max-rays 8192
            done
            # Rays where the relative error is (the creases, which p95 counts), the filter
            # where the neighbours share them (the open surfaces, which f_diff counts).
            for t in 0.2 0.14 0.1 0.08 0.06 0.04 0.03 0.02; do
                hmdist_point hmdist_adaptive_denoise "" --method adaptive --tolerance "$t" --loosen 0.5 \
                    --min-rays 64 --max-rays 8192 --denoise
            done
        done
        "$venv/bin/python" "$here/denoise_pictures.py" "$reference" "$work/embree-256.exr" "$work/denoise-64.exr" \
            "$("$hmdist" scene info "$scene" | awk -F': *' '/display scale/ { print $2 }')" "$pictures/$name-denoise.png"
        python3 "$here/accuracy_summary.py" "$log" "$name" "$side" "$threads"
    done
    exit 0
fi

if [ "$mode" = e2e ]; then
    for case in $cases; do
        IFS=: read -r scene side n <<<"$case"
        name="$(basename "$scene")"
        points="$work/$name-$side.hmdp"
        obj="$work/$name.obj"
        [ -f "$points" ] || "$gather_rays" points "$scene" "$side" "$points"
        [ -f "$obj" ] || "$hmdist" scene export "$scene" "$obj" >/dev/null
        log="$work/$name-$side-$n-e2e.log"
        : >"$log"
        for _ in $(seq "$runs"); do
            "$hmdist" render --quiet --scene "$scene" --size "${side}x$side" --rays "$n" --threads "$threads" \
                --sampler grid --out "$work/e2e.exr" --json "$work/e2e.json" >/dev/null
            python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); s = d["seconds"]
print("hmdist build_s %.3f gather_s %.3f mrays_per_s %.3f total_s %.3f kernel %s bvh %s" % (
    s["accel_build"], s["estimate"], d["mrays_per_s"], s["total"], d["kernel"], d["bvh"]))' "$work/e2e.json" >>"$log"
            for build in robust fast; do
                for cast in $casts; do
                    "$work/embree_gather" "$obj" "$points" "$n" "$threads" "$build" "$cast" >>"$log"
                done
            done
        done
        python3 - "$log" "$case" "$threads" <<'PY'
import statistics, sys
log, case, threads = sys.argv[1], sys.argv[2], sys.argv[3]
runs = {}
for line in open(log):
    words = line.split()
    runs.setdefault(words[0], []).append(dict(zip(words[1::2], words[2::2])))
med = lambda name, key: statistics.median(float(r.get(key, 0)) for r in runs[name])
ours = med("hmdist", "mrays_per_s")
print(f"\n{case} end to end ({threads} threads, medians of {len(runs['hmdist'])} interleaved runs)")
print(f"{'gather':<26} {'build_s':>8} {'gen_s':>6} {'gather_s':>9} {'Mrays/s':>8} {'hmdist ÷':>9}")
for name in runs:
    m = med(name, "mrays_per_s")
    print(f"{name:<26} {med(name, 'build_s'):>8.2f} {med(name, 'gen_s'):>6.2f} {med(name, 'gather_s'):>9.2f} {m:>8.2f} {ours / m:>9.2f}")
peers = [name for name in runs if name.startswith("embree")]
for build in ("robust", "fast"):
    mine = [name for name in peers if name.startswith(f"embree_e2e_{build}_")]
    if mine:
        best = max(mine, key=lambda name: med(name, "mrays_per_s"))
        print(f"fastest Embree, {build} build: {best} — hmdist ÷ it {ours / med(best, 'mrays_per_s'):.2f}")
PY
    done
    exit 0
fi

for case in $cases; do
    IFS=: read -r scene side n <<<"$case"
    name="$(basename "$scene")"
    rays="$work/$name-$side-$n.hmdr"
    obj="$work/$name.obj"
    if [ "$scene" = sphere5m ]; then
        mkdir -p "$work/sphere5m"
        [ -f "$work/sphere5m/sphere.toml" ] || "$gather_rays" sphere 9 "$work/sphere5m"
        obj="$work/sphere5m/sphere.obj"
        scene="$work/sphere5m/sphere.toml"
    fi
    [ -f "$rays" ] || "$gather_rays" write "$scene" "$side" "$n" "$rays"
    [ -f "$obj" ] || "$hmdist" scene export "$scene" "$obj" >/dev/null
    log="$work/$name-$side-$n.log"
    : >"$log"
    for _ in $(seq "$runs"); do
        "$gather_rays" cast "$scene" "$rays" >>"$log"
        "$work/embree_cast" "$obj" "$rays" "$threads" robust >>"$log"
        "$work/embree_cast" "$obj" "$rays" "$threads" fast >>"$log"
        "$venv/bin/python" "$here/open3d_cast.py" "$obj" "$rays" "$threads" >>"$log"
    done
    python3 - "$log" "$case" "$threads" <<'PY'
import statistics, sys
log, case, threads = sys.argv[1], sys.argv[2], sys.argv[3]
runs = {}
for line in open(log):
    words = line.split()
    fields = dict(zip(words[1::2], words[2::2]))
    runs.setdefault(words[0], []).append(fields)
med = lambda name, key: statistics.median(float(r[key]) for r in runs[name])
ours = med("hmdist", "mrays_per_s")
print(f"\n{case} ({threads} threads, medians of {len(runs['hmdist'])} interleaved runs)")
total = lambda name: statistics.median(float(r["build_s"]) + float(r["trace_s"]) for r in runs[name])
print(f"{'caster':<14} {'build_s':>8} {'Mrays/s':>8} {'escaped':>8} {'hmdist ÷':>9} {'build+trace_s':>14} {'hmdist ÷':>9}")
for name in runs:
    m = med(name, "mrays_per_s")
    escaped = int(runs[name][0]["escaped"])
    print(f"{name:<14} {med(name, 'build_s'):>8.2f} {m:>8.2f} {escaped:>8} {ours / m:>9.2f} "
          f"{total(name):>14.2f} {total(name) / total('hmdist'):>9.2f}")
PY
done
