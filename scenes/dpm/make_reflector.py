#!/usr/bin/env python3
"""Writes reflector.obj, the curved mirror of scenes/dpm/reflector.xml (paper 003 Fig. 6): a concave
spherical cap, deterministic (a closed formula, no random numbers).

Local frame: the cap's vertex at the origin, its axis +z, the centre of curvature at (0, 0, RADIUS), the
mirror side facing +z. The cap covers the square [-HALF, HALF]^2 in x, y on a GRID x GRID grid of quads
(2 GRID^2 triangles), with exact (smooth) sphere normals pointing to the centre of curvature. Run from the
repository root:
    python3 scenes/dpm/make_reflector.py
"""
import os

import numpy as np

RADIUS = 2.6  # radius of curvature (focal length 1.3)
HALF = 0.55  # half side of the cap's square aperture
GRID = 40  # quads per side: 3200 triangles

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "reflector.obj")


def spherical_cap(radius, half, grid):
    """Vertices, unit normals (towards the centre of curvature) and counter-clockwise (+z facing) faces."""
    t = np.linspace(-half, half, grid + 1)
    x, y = np.meshgrid(t, t, indexing="xy")
    z = radius - np.sqrt(radius**2 - x**2 - y**2)
    v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    n = np.array([0.0, 0.0, radius]) - v
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    faces = []
    for j in range(grid):
        for i in range(grid):
            a = j * (grid + 1) + i
            b, c, d = a + 1, a + grid + 1, a + grid + 2
            faces += [(a, b, d), (a, d, c)]
    return v, n, np.array(faces, dtype=np.int64)


def write_obj(path, v, n, f, header):
    with open(path, "w") as out:
        out.write(f"# {header}\n")
        for p in v:
            out.write(f"v {p[0]:.7f} {p[1]:.7f} {p[2]:.7f}\n")
        for q in n:
            out.write(f"vn {q[0]:.7f} {q[1]:.7f} {q[2]:.7f}\n")
        for a, b, c in f + 1:
            out.write(f"f {a}//{a} {b}//{b} {c}//{c}\n")


if __name__ == "__main__":
    v, n, f = spherical_cap(RADIUS, HALF, GRID)
    write_obj(OUT, v, n, f, f"concave spherical cap, radius of curvature {RADIUS}, square aperture "
              f"[-{HALF}, {HALF}]^2, {len(f)} triangles (scenes/dpm/make_reflector.py)")
    print(f"wrote {OUT}: {len(v)} vertices, {len(f)} triangles")
