"""Render the built-in `cube` scene with hmdist and plot H with matplotlib.

    python python/examples/render_cube.py [out.png]

matplotlib is optional: without it the script prints H's statistics and says how to get it
(pip install matplotlib).
"""

import sys

import numpy as np

import hmdist

scene = hmdist.Scene.builtin("cube")
H, report = scene.render(method="gather", rays=64, size=(256, 256), seed=1)
finite = H[np.isfinite(H)]
print(f"{report['scene']}: {report['width']}x{report['height']}, {report['rays_cast']} rays in "
      f"{report['seconds']['total']:.2f} s; H from {finite.min():.3f} to {finite.max():.3f}, "
      f"median {np.median(finite):.3f}")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: pip install matplotlib, then run this again for a picture")
    sys.exit(0)

out = sys.argv[1] if len(sys.argv) > 1 else "cube-hmd.png"
plt.imshow(H, cmap="viridis", vmax=np.percentile(finite, 99))
plt.colorbar(label="H (scene units)")
plt.title("harmonic mean distance, cube")
plt.savefig(out, dpi=120)
print(f"wrote {out}")
