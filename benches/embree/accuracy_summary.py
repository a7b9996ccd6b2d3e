"""The summary of `compare.sh --accuracy`: per side its f_diff and seconds by N, then the
seconds each needs for f_diff <= T, T at Embree's f_diff with 64, 256 and 1,024 rays.

Usage: python3 accuracy_summary.py LOG SCENE SIDE THREADS (compare.sh runs it).
Log lines: `SIDE n N gather_s S [f_diff F]` per run, and `embree n N f_diff F` once per N
(Embree's H is the same for every cast variant; its seconds are the fastest variant's).
"""

import math
import statistics
import sys

TARGETS = (64, 256, 1024)


def read(log):
    seconds, errors = {}, {}
    for line in open(log):
        words = line.split()
        side, fields = words[0], dict(zip(words[1::2], words[2::2]))
        n = int(fields["n"])
        if side.startswith("embree_e2e_"):
            seconds.setdefault(("embree", n), {}).setdefault(side, []).append(float(fields["gather_s"]))
        elif side == "embree":
            errors[("embree", n)] = float(fields["f_diff"])
        else:
            seconds.setdefault((side, n), {}).setdefault(side, []).append(float(fields["gather_s"]))
            if "f_diff" in fields:
                errors[(side, n)] = float(fields["f_diff"])
    curves = {}
    for (side, n), variants in seconds.items():
        fastest = min(variants, key=lambda v: statistics.median(variants[v]))
        curves.setdefault(side, []).append((n, statistics.median(variants[fastest]), errors[(side, n)], fastest))
    return {side: sorted(points) for side, points in curves.items()}


def seconds_to(curve, target):
    """Seconds for f_diff <= target: log-log between the two N that bracket it (the end
    segments extended beyond the N measured, marked with a *)."""
    points = [(math.log(e), math.log(s)) for _, s, e, _ in curve]
    for i in range(1, len(points)):
        (e0, s0), (e1, s1) = points[i - 1], points[i]
        if e1 <= math.log(target) or i == len(points) - 1:
            break
    at = s0 + (s1 - s0) * (math.log(target) - e0) / (e1 - e0)
    outside = not (min(e0, e1) <= math.log(target) <= max(e0, e1))
    return math.exp(at), outside


def main():
    log, scene, side, threads = sys.argv[1:5]
    curves = read(log)
    names = {"embree": "Embree (jittered grid, fastest cast)", "hmdist_gather": "hmdist render (defaults: sobol)",
             "hmdist_adaptive": "hmdist adaptive (--abs-tolerance, loosen 1; N: mean rays cast)"}
    print(f"\n{scene} {side}², {threads} threads: f_diff and gather seconds by N (median of runs)")
    for side_name, curve in curves.items():
        print(f"  {names.get(side_name, side_name)}")
        for n, s, e, fastest in curve:
            extra = f"  ({fastest})" if side_name == "embree" else ""
            print(f"    N={n:5} f_diff {e:.4f}  {s:8.3f} s{extra}")
    embree = {n: e for n, _, e, _ in curves["embree"]}
    print(f"  seconds to f_diff <= T (* extrapolated); hmdist ÷ Embree")
    for n in TARGETS:
        if n not in embree:
            continue
        target = embree[n]
        row = [f"    T = {target:.4f} (Embree's N={n}):"]
        base, _ = seconds_to(curves["embree"], target)
        for side_name in ("embree", "hmdist_gather", "hmdist_adaptive"):
            if side_name not in curves:
                continue
            s, outside = seconds_to(curves[side_name], target)
            ratio = "" if side_name == "embree" else f" (x{s / base:.2f})"
            row.append(f"{side_name} {s:.3f} s{'*' if outside else ''}{ratio}")
        print("  ".join(row))


if __name__ == "__main__":
    main()
