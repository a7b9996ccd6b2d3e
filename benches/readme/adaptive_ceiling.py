"""The README's "what it buys, and what it does not" figures (adaptive gathering, issue #25).

1. The ceiling of any allocation at equal f_diff: if pixel i's error were s_i / N^alpha with
   s_i known exactly, rays split as N_i ~ s_i^(1/(1+alpha)) save, at equal mean error,
   (sum s_i / sum s_i N_i^-alpha)^(1/alpha) against the same N everywhere (N_i normalised to
   a mean of 1). s_i is the standard error of H from 8 independent replicates of 256 sobol
   rays per pixel (gather --sampler sobol --rays 2048 --rounds 8).
2. How well adaptive's error estimate (the spread of consecutive blocks of one sequence:
   adaptive --sampler sobol, stopped at its first check, 8 blocks of 32) ranks the pixels
   against their true relative error (the spread of H of gather --sampler sobol --rays 256
   over 16 seeds), and how far the true error lies below the median pixel's at the 95th
   percentile.

Usage: python benches/readme/adaptive_ceiling.py [SIZE]   (default 48; the README's ceilings
are at 256, its estimate figures at 48). Needs the hmdist Python package (pip install ./python).
"""

import sys

import numpy as np

import hmdist


def ceiling(scene, size):
    _, report, aov = scene.render(size=(size, size), rays=2048, rounds=8, sampler="sobol", seed=5,
                                  aov=["relerr"])
    hmd, _ = scene.render(size=(size, size), rays=2048, sampler="sobol", seed=6)
    keep = np.isfinite(hmd) & (hmd > 0) & np.isfinite(aov["relerr"])
    s = aov["relerr"][keep] * hmd[keep]
    top = np.sort(s)[::-1]
    print(f"  the tenth of the pixels with the largest s_i holds {top[: len(top) // 10].sum() / top.sum():.0%} of sum s_i")
    for alpha in (0.5, 0.75):
        n = s ** (1 / (1 + alpha))
        n /= n.mean()
        saving = (s.sum() / (s * n**-alpha).sum()) ** (1 / alpha)
        print(f"  alpha = {alpha}: the best split saves x{saving:.2f} at equal mean error")


def estimate(scene, size):
    seeds = range(1, 17)
    blocks = np.mean([scene.render(size=(size, size), method="adaptive", sampler="sobol", tolerance=1e9,
                                   min_rays=256, max_rays=256, seed=seed, aov=["relerr"])[2]["relerr"]
                      for seed in seeds[:6]], axis=0)
    hmd = np.array([scene.render(size=(size, size), rays=256, sampler="sobol", backend="cpu", seed=seed)[0]
                    for seed in seeds])
    true = hmd.std(axis=0, ddof=1) / hmd.mean(axis=0)
    keep = np.isfinite(blocks) & np.isfinite(true) & (true > 0) & (blocks > 0)
    rank = lambda x: np.argsort(np.argsort(x))
    spearman = np.corrcoef(rank(blocks[keep]), rank(true[keep]))[0, 1]
    ratio = np.quantile(true[keep] / blocks[keep], [0.05, 0.95])
    q50, q95 = np.quantile(true[keep], [0.5, 0.95])
    print(f"  blocks' estimate against the true relative error: Spearman {spearman:.2f}, "
          f"true / estimated {ratio[0]:.2f}-{ratio[1]:.2f} (5th-95th percentile); "
          f"true error's 95th percentile / median {q95 / q50:.1f}")


if __name__ == "__main__":
    size = int(sys.argv[1]) if len(sys.argv) > 1 else 48
    for name in ("cube", "hall"):
        scene = hmdist.Scene.builtin(name)
        print(f"{name}, {size}²:")
        ceiling(scene, size)
        estimate(scene, size)
