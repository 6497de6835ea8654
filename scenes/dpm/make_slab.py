#!/usr/bin/env python3
"""Writes slab_top.obj, the bumpy top face of the glass slab of scenes/dpm/slab.xml: the height field
y = BASE + h(x, z) over [-HALF, HALF]^2, deterministic (a closed formula, no random numbers), with

    h(x, z) = A1 cos(K x + 0.3) cos(K z + 0.7) + A2 sin(1.7 K x - 1.1 K z),

a GRID x GRID grid of quads (2 GRID^2 triangles) and exact (smooth) normals (-h_x, 1, -h_z) / |.|, facing
up (out of the glass). The slab's flat bottom face is a `rectangle` in the scene. Run from the repository
root:
    python3 scenes/dpm/make_slab.py
"""
import os

import numpy as np

from make_reflector import write_obj

BASE = 2.2  # mean height of the top face (the bottom face is at y = 2)
HALF = 1.0  # half side of the face
GRID = 64  # quads per side: 8192 triangles
K = 2.0 * np.pi / 0.5  # wavelength 0.5
A1, A2 = 0.0030, 0.0012  # amplitudes: smooth focusing, no caustic folds on the floor

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "slab_top.obj")


def height_field_mesh(x, z, h, hx, hz, base):
    """The mesh of y = base + h(x, z) sampled on a square grid (x, z from np.meshgrid(t, t, indexing="xy")) with
    the gradient (hx, hz): vertices, exact unit normals (-h_x, 1, -h_z) / |.| and faces whose
    (counter-clockwise seen from above) normals face +y."""
    grid = x.shape[0] - 1
    v = np.stack([x, base + h, z], axis=-1).reshape(-1, 3)
    n = np.stack([-hx, np.ones_like(h), -hz], axis=-1).reshape(-1, 3)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    faces = []
    for j in range(grid):
        for i in range(grid):
            a = j * (grid + 1) + i  # (x_i, z_j)
            b, c, d = a + 1, a + grid + 1, a + grid + 2
            faces += [(a, d, b), (a, c, d)]  # (b - a) x (d - a) = +x x (+x +z) points to -y: reversed
    return v, n, np.array(faces, dtype=np.int64)


def height_field(half, grid):
    """This slab's bumpy top face (height_field_mesh of two products of cosines and a diagonal sine)."""
    t = np.linspace(-half, half, grid + 1)
    x, z = np.meshgrid(t, t, indexing="xy")
    h = A1 * np.cos(K * x + 0.3) * np.cos(K * z + 0.7) + A2 * np.sin(1.7 * K * x - 1.1 * K * z)
    diagonal = np.cos(1.7 * K * x - 1.1 * K * z)
    hx = -A1 * K * np.sin(K * x + 0.3) * np.cos(K * z + 0.7) + A2 * 1.7 * K * diagonal
    hz = -A1 * K * np.cos(K * x + 0.3) * np.sin(K * z + 0.7) - A2 * 1.1 * K * diagonal
    return height_field_mesh(x, z, h, hx, hz, BASE)


if __name__ == "__main__":
    v, n, f = height_field(HALF, GRID)
    write_obj(OUT, v, n, f, f"bumpy top face of a glass slab, height {BASE} + h(x, z) over "
              f"[-{HALF}, {HALF}]^2, {len(f)} triangles (scenes/dpm/make_slab.py)")
    print(f"wrote {OUT}: {len(v)} vertices, {len(f)} triangles")
