"""Adaptive gathering against fixed N, at equal error (issue #54): the stop (the best two
schemes of docs/guide.md) against two oracles of how rays could be split among the pixels.

Per scene at SIZE² (default 256; `cube`, `hall` and `columns`, benches/scenes/columns.py):
- a sobol reference of 4,096 rays per pixel (its own seed);
- fixed sobol gathers at N = 64 ... 1,024: f_diff and the 95th percentile of |ΔH|/H against
  rays, interpolated log-log; every other image is placed on those curves: its saving is the
  rays a fixed gather needs for the same error over the rays it cast (pilot included);
- the model's ceiling (adaptive_ceiling.py's): if each pixel's error were s_i N^-1/2 with s_i
  from 8 replicates of 256 rays, the best split would save this much at equal mean error;
- the measured oracle: rays split as N_i ∝ e_i^(2/3), e_i each pixel's true error (the
  spread of H over 16 seeds of 256 rays), rounded to a ladder of half octaves, each pixel
  taking its H from the sobol gather of its N_i: what a budget split by a pilot's error
  estimates could reach with a perfect pilot (with a real one, 32 rays a pixel, it did worse
  than fixed N: the branch `adaptive-budget`).

Usage: python benches/readme/adaptive_oracle.py [SIZE] [SCENES]. Needs the hmdist Python
package (`maturin develop --release -m python/Cargo.toml`, or pip install ./python). About 4
minutes per scene at 256² on 2 cores.
"""

import os
import sys
import tempfile

import numpy as np

import hmdist

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "scenes"))
import columns  # noqa: E402

FIXED = [64, 128, 256, 512, 1024]
BUDGETS = [128, 256, 512]
MIN_RAYS, MAX_RAYS = 32, 2048
LADDER = [int(round(32 * 2 ** (k / 2) / 4)) * 4 for k in range(13)]  # 32 ... 2,048
STOPS = [("stop, relative T, loosen 0.5", {"loosen": 0.5, "min_rays": 64}, "tolerance", (0.1, 0.05, 0.025)),
         ("stop, absolute A, loosen 1", {"loosen": 1.0, "min_rays": 64, "tolerance": 0.0}, "abs_tolerance",
          (0.002, 0.001, 0.0005))]


def errors(reference, image, l_diag):
    """f_diff and the 95th percentile of |ΔH|/H over pixels finite in both."""
    keep = np.isfinite(reference) & np.isfinite(image) & (reference > 0)
    relative = np.abs(image[keep] - reference[keep]) / reference[keep]
    return hmdist.f_diff(reference, image, l_diag), float(np.quantile(relative, 0.95))


def rays_for(curve, error):
    """The rays a fixed gather needs for `error`: log-log interpolation on (rays, error)
    points, extrapolated with the end segments' slopes."""
    n, e = np.log([c[0] for c in curve]), np.log([c[1] for c in curve])
    i = np.clip(np.searchsorted(-e, -np.log(error)), 1, len(e) - 1)
    slope = (n[i] - n[i - 1]) / (e[i] - e[i - 1])
    return float(np.exp(n[i - 1] + slope * (np.log(error) - e[i - 1])))


def model_ceiling(render):
    """The model's saving at equal mean error (alpha = 0.5): rays split by s_i."""
    _, _, aov = render(rays=2048, rounds=8, seed=5, aov=["relerr"])
    hmd, _ = render(rays=2048, seed=6)
    keep = np.isfinite(hmd) & (hmd > 0) & np.isfinite(aov["relerr"])
    s = aov["relerr"][keep] * hmd[keep]
    n = s ** (1 / 1.5)
    n /= n.mean()
    return (s.sum() / (s * n**-0.5).sum()) ** 2


def split(weights, mean):
    """N_i = clamp(c w_i, MIN_RAYS, MAX_RAYS) with mean `mean` (bisection on c)."""
    low, high = 0.0, 1.0
    while np.clip(high * weights, MIN_RAYS, MAX_RAYS).mean() < mean:
        high *= 2
    for _ in range(100):
        c = (low + high) / 2
        low, high = (c, high) if np.clip(c * weights, MIN_RAYS, MAX_RAYS).mean() < mean else (low, c)
    return np.clip(high * weights, MIN_RAYS, MAX_RAYS)


def measured_oracle(render, reference, budgets):
    """Images of the oracle's split at each budget, and the rays each cast per pixel."""
    seeds = np.array([render(rays=256, seed=100 + k)[0] for k in range(16)])
    keep = np.isfinite(reference)
    weights = np.nan_to_num(seeds.std(axis=0, ddof=1), nan=0.0)[keep] ** (2 / 3)
    ladder = {n: render(rays=n, seed=1)[0][keep] for n in LADDER}
    images = []
    for budget in budgets:
        wanted = split(weights, budget)
        rungs = np.array(LADDER)[np.argmin(np.abs(np.log(wanted[:, None] / np.array(LADDER)[None, :])), axis=1)]
        image = np.full(reference.shape, np.nan, np.float32)
        image[keep] = np.choose(np.searchsorted(LADDER, rungs), [ladder[n] for n in LADDER])
        images.append((budget, image, rungs.mean()))
    return images


def study(name, scene, size):
    l_diag = scene.info["l_diag"]
    render = lambda **p: scene.render(None, size=(size, size), **p)
    reference, _ = render(rays=4096, seed=1000003)
    fixed = [(n, *errors(reference, render(rays=n, seed=1)[0], l_diag)) for n in FIXED]
    mean_curve, p95_curve = [(n, f) for n, f, _ in fixed], [(n, p) for n, _, p in fixed]
    print(f"\n{name}, {size}²: the model's ceiling x{model_ceiling(render):.2f} at equal mean error")
    print("  fixed sobol: " + "; ".join(f"N={n} f_diff {f:.4f} p95 {p:.4f}" for n, f, p in fixed))

    def line(label, image, cast):
        f, p = errors(reference, image, l_diag)
        print(f"  {label:42} {cast:7.1f} rays: f_diff {f:.4f} (x{rays_for(mean_curve, f) / cast:.2f}), "
              f"p95 {p:.4f} (x{rays_for(p95_curve, p) / cast:.2f})", flush=True)

    for budget, image, cast in measured_oracle(render, reference, BUDGETS):
        line(f"measured oracle, N={budget}", image, cast)
    for label, params, knob, values in STOPS:
        for value in values:
            image, report = render(method="adaptive", max_rays=MAX_RAYS, seed=1, **params, **{knob: value})
            line(f"{label}, {value}", image, report["mean_rays_per_pixel"])


if __name__ == "__main__":
    size = int(sys.argv[1]) if len(sys.argv) > 1 else 256
    names = sys.argv[2].split(",") if len(sys.argv) > 2 else ["cube", "hall", "columns"]
    for name in names:
        if name == "columns":
            with tempfile.TemporaryDirectory() as directory:
                study(name, hmdist.Scene.load(columns.write(directory)), size)
        else:
            study(name, hmdist.Scene.builtin(name), size)
