#!/usr/bin/env python3
"""The sphere's left edge in Mitsuba's published picture of mitsuba-data's
docs/scenes/shape_sphere_basic.xml (docs/images/render/shape_sphere_basic.jpg, 960 x 720):
for rows 45, 60, ..., 480, the first column of the run of sphere pixels through column 470,
a sphere pixel being one whose blue exceeds the mean of its red and green by more than 22.
Prints the (row, column) pairs tests/mitsuba.rs holds as PUBLISHED_LEFT_EDGE, and the top row.

    python3 scripts/mitsuba-silhouette.py shape_sphere_basic.jpg

Needs Pillow and NumPy.
"""
import sys

import numpy as np
from PIL import Image

rgb = np.asarray(Image.open(sys.argv[1]).convert("RGB")).astype(int)
blue = rgb[..., 2] - (rgb[..., 0] + rgb[..., 1]) / 2 > 22
edges = []
for row in range(45, 481, 15):
    x = 470
    if not blue[row, x]:
        sys.exit(f"row {row}: column {x} is not on the sphere")
    while x > 0 and blue[row, x - 1]:
        x -= 1
    edges.append((row, x))
print(", ".join(f"({r}, {c})" for r, c in edges))
top = next(r for r in range(blue.shape[0]) if blue[r, 461:502].any())
print("top row", top)
