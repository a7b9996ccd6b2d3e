"""The summary of `compare.sh --accuracy`: per side its errors and seconds by N, then the
seconds each needs for f_diff <= T, T at Embree's f_diff with 64, 256 and 1,024 rays, and
its p95 there.

Usage: python3 accuracy_summary.py LOG SCENE SIDE THREADS (compare.sh runs it).
Log lines: `SIDE n N gather_s S [f_diff F bias B creases C rest R p95 P]` per run (errors in
the first), `embree n N f_diff F ...` and `embree_oidn n N f_diff F ...` once per N (Embree's
H is the same for every cast variant; its seconds are the fastest variant's), `oidn n N
oidn_s S` per run (the filter's seconds, added to Embree's for Embree + OIDN).
"""

import math
import statistics
import sys

TARGETS = (64, 256, 1024)
ERRORS = ("f_diff", "bias", "creases", "rest", "p95")
NAMES = {
    "embree": "Embree (jittered grid, fastest cast)",
    "embree_oidn": "Embree + Intel Open Image Denoise (1/t, normals as the guide)",
    "hmdist_gather": "hmdist render (defaults: sobol)",
    "hmdist_denoise": "hmdist render --denoise",
    "hmdist_adaptive": "hmdist adaptive (--abs-tolerance, loosen 1; N: mean rays cast)",
    "hmdist_adaptive_denoise": "hmdist adaptive --denoise (--tolerance, loosen 0.5; N: mean rays cast)",
}


def read(log):
    seconds, errors, oidn = {}, {}, {}
    for line in open(log):
        words = line.split()
        side, fields = words[0], dict(zip(words[1::2], words[2::2]))
        n = int(fields["n"])
        if side.startswith("embree_e2e_"):
            seconds.setdefault(("embree", n), {}).setdefault(side, []).append(float(fields["gather_s"]))
        elif side == "oidn":
            oidn.setdefault(n, []).append(float(fields["oidn_s"]))
        elif side in ("embree", "embree_oidn"):
            errors[(side, n)] = {k: float(fields[k]) for k in ERRORS}
        else:
            seconds.setdefault((side, n), {}).setdefault(side, []).append(float(fields["gather_s"]))
            if "f_diff" in fields:
                errors[(side, n)] = {k: float(fields[k]) for k in ERRORS}
    curves = {}
    for (side, n), variants in sorted(seconds.items()):
        fastest = min(variants, key=lambda v: statistics.median(variants[v]))
        s = statistics.median(variants[fastest])
        curves.setdefault(side, []).append((n, s, errors[(side, n)], fastest))
        if side == "embree" and n in oidn:
            curves.setdefault("embree_oidn", []).append(
                (n, s + statistics.median(oidn[n]), errors[("embree_oidn", n)], "+ oidn"))
    return {side: sorted(points, key=lambda p: p[0]) for side, points in curves.items()}


def at_error(curve, target, value):
    """`value(point)` (log-log) where f_diff = target, between the two N that bracket it (the
    caller checks that two do)."""
    points = [(math.log(e["f_diff"]), math.log(max(value(p), 1e-12))) for p in curve for e in [p[2]]]
    for i in range(1, len(points)):
        (e0, _), (e1, _) = points[i - 1], points[i]
        if e1 <= math.log(target) or i == len(points) - 1:
            break
    (e0, v0), (e1, v1) = points[i - 1], points[i]
    at = v0 + (v1 - v0) * (math.log(target) - e0) / (e1 - e0)
    outside = not (min(e0, e1) <= math.log(target) <= max(e0, e1))
    return math.exp(at), outside


def main():
    log, scene, side, threads = sys.argv[1:5]
    curves = read(log)
    print(f"\n{scene} {side}², {threads} threads: errors (first run) and gather seconds by N (median of runs)")
    for side_name, curve in curves.items():
        print(f"  {NAMES.get(side_name, side_name)}")
        for n, s, e, fastest in curve:
            extra = f"  ({fastest})" if side_name.startswith("embree") else ""
            print(f"    N={n:5} f_diff {e['f_diff']:.4f} bias {e['bias']:+.4f} creases {e['creases']:.4f} "
                  f"rest {e['rest']:.4f} p95 {e['p95']:.4f}  {s:8.3f} s{extra}")
    embree = {n: e for n, _, e, _ in curves["embree"]}
    print("  seconds to f_diff <= T (log-log between the N measured), x Embree's; p95 there, against Embree's at N")
    for n in TARGETS:
        if n not in embree:
            continue
        target = embree[n]["f_diff"]
        print(f"    T = {target:.4f} (Embree's N={n}, p95 {embree[n]['p95']:.4f}):")
        base, _ = at_error(curves["embree"], target, lambda p: p[1])
        for side_name in ("embree", "embree_oidn", "hmdist_gather", "hmdist_denoise", "hmdist_adaptive",
                          "hmdist_adaptive_denoise"):
            if side_name not in curves:
                continue
            curve = curves[side_name]
            first, best = curve[0], min(curve, key=lambda p: p[2]["f_diff"])
            if first[2]["f_diff"] <= target:
                # Below T at the fewest rays measured: at most that many seconds (not
                # extrapolated towards fewer rays).
                s, p95 = first[1], first[2]["p95"]
                print(f"      {side_name:16} <= {s:.3f} s (x{s / base:.2f} at most; N={first[0]} is below T)  p95 {p95:.4f}")
                continue
            if best[2]["f_diff"] > target:
                print(f"      {side_name:16} not reached: its least f_diff is {best[2]['f_diff']:.4f} (N={best[0]})")
                continue
            s, _ = at_error(curve, target, lambda p: p[1])
            p95, _ = at_error(curve, target, lambda p: p[2]["p95"])
            print(f"      {side_name:16} {s:8.3f} s (x{s / base:.2f})  p95 {p95:.4f}")
        print(f"    the fewest seconds of a measured image with f_diff <= {target:.4f} and p95 <= {embree[n]['p95']:.4f}:")
        for side_name, curve in curves.items():
            both = [p for p in curve if p[2]["f_diff"] <= target and p[2]["p95"] <= embree[n]["p95"]]
            if both:
                p = min(both, key=lambda p: p[1])
                print(f"      {side_name:24} {p[1]:8.3f} s (x{p[1] / base:.2f}) at N={p[0]}: "
                      f"f_diff {p[2]['f_diff']:.4f}, p95 {p[2]['p95']:.4f}")
            else:
                print(f"      {side_name:24} none")


if __name__ == "__main__":
    main()
