"""`columns`: a third closed scene for the benchmarks, beside `cube` and `hall` — a room 12 x 4 x 9
with six square columns, a table on four legs, a ceiling beam and four spheres (3,996
triangles), seen from a corner. Closed, so no gather ray escapes.

Usage: python3 benches/scenes/columns.py DIR   # writes DIR/columns.obj and DIR/columns.toml
(plain Python, no packages).
"""

import math
import os
import sys


def box(lo, hi):
    """A box's 8 corners and 12 triangles."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return v, [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]


def sphere(centre, radius, rings=16, segments=32):
    """A UV sphere."""
    cx, cy, cz = centre
    v = [(cx, cy + radius, cz), (cx, cy - radius, cz)]
    for i in range(1, rings):
        t = math.pi * i / rings
        for j in range(segments):
            p = 2 * math.pi * j / segments
            v.append((cx + radius * math.sin(t) * math.cos(p), cy + radius * math.cos(t),
                      cz + radius * math.sin(t) * math.sin(p)))
    ring = lambda i, j: 2 + (i - 1) * segments + j % segments
    f = [(0, ring(1, j + 1), ring(1, j)) for j in range(segments)]
    f += [(1, ring(rings - 1, j), ring(rings - 1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        for j in range(segments):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            f += [(a, b, c), (a, c, d)]
    return v, f


def parts():
    yield box((-6, 0, -4.5), (6, 4, 4.5))
    for x in (-3.5, 0, 3.5):
        for z in (-2, 2):
            yield box((x - 0.3, 0, z - 0.3), (x + 0.3, 4, z + 0.3))
    yield box((-1.5, 0.9, -0.6), (1.5, 1.0, 0.6))
    for x in (-1.4, 1.4):
        for z in (-0.5, 0.5):
            yield box((x - 0.05, 0, z - 0.05), (x + 0.05, 0.9, z + 0.05))
    yield box((-6, 3.4, -0.2), (6, 4, 0.2))
    for x, z, r in ((-4.5, 3.5, 0.5), (2, -3.5, 0.8), (4.8, 0.5, 0.3), (0.2, 1.3, 0.3)):
        yield sphere((x, r, z), r)


def write(directory):
    os.makedirs(directory, exist_ok=True)
    base = 0
    with open(os.path.join(directory, "columns.obj"), "w") as obj:
        for v, f in parts():
            obj.writelines(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
            obj.writelines(f"f {a + base + 1} {b + base + 1} {c + base + 1}\n" for a, b, c in f)
            base += len(v)
    with open(os.path.join(directory, "columns.toml"), "w") as toml:
        toml.write('[[mesh]]\npath = "columns.obj"\n[camera]\neye = [-5.5, 2.5, 0.0]\n'
                   'target = [1.0, 0.9, -0.8]\nfov_y_deg = 70.0\n')
    return os.path.join(directory, "columns.toml")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python3 benches/scenes/columns.py DIR")
    print(write(sys.argv[1]))
