#!/usr/bin/env bash
# Copies an experiment run's results from OUT into DEST for the repository (issue #22): the
# tables (Markdown, CSV), plots (SVG), index.html, the plan and plan-against-run files, and the
# picture grids, each PNG over 2 MB downscaled (Lanczos) until it is under 2 MB (at paper scale
# a grid of 1024² tiles is 15 MB). No image cache, no EXR.
#
#   docs/paper-scale/publish.sh OUT DEST     # e.g. /tmp/paper-cube docs/paper-scale/cube
#
# Needs Python 3 with Pillow (pip install pillow).
set -euo pipefail
out="$1"
dest="$2"
mkdir -p "$dest"
shopt -s nullglob
for f in "$out"/*.md "$out"/*.csv "$out"/*.svg "$out"/*.json "$out"/index.html; do
    cp "$f" "$dest/"
done
for f in "$out"/*.png; do
    python3 - "$f" "$dest/$(basename "$f")" <<'PY'
import os, sys
from PIL import Image

source, target = sys.argv[1], sys.argv[2]
limit = 2 * 1024 * 1024
image = Image.open(source)
scale = 1
while True:
    size = (max(1, image.width // scale), max(1, image.height // scale))
    small = image if scale == 1 else image.resize(size, Image.LANCZOS)
    small.save(target + ".tmp.png", optimize=True)
    if os.path.getsize(target + ".tmp.png") <= limit or min(size) <= 64:
        break
    scale *= 2
os.replace(target + ".tmp.png", target)
print(f"{os.path.basename(target)}: {image.width}x{image.height} -> {size[0]}x{size[1]}, "
      f"{os.path.getsize(target) / 1e6:.1f} MB")
PY
done
