#!/usr/bin/env python3
"""Writes the top faces of the glass slab of scenes/dpm/image/scene.xml, height fields y = BASE + h(x, z) over
[-HALF, HALF]^2 on a GRID x GRID grid of quads ((GRID + 1)^2 height values), deterministic (closed formulas):

    flat.obj    h = 0, the initial slab of the inverse problem;
    bumps.obj   h = sum_i A_i exp(-|p - c_i|^2 / (2 s_i^2)), three Gaussian bumps (one a dip), the known
                target of config.json.

and ring.hdr, the drawn target image of config_ring.json (RES x RES, Radiance RGBE): a bright ring on a
dimmer floor whose mean is the flat slab's radiance, so that a height field can reach it by moving light.

Both have the same vertices in x and z, in the same order, and exact (smooth) normals (-h_x, 1, -h_z) / |.|
(the renderer recomputes the vertex normals of a mesh whose vertex_positions are written). Run from the repository root:
    /usr/bin/python3 scenes/dpm/image/make_slab.py
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from make_reflector import write_obj  # noqa: E402
from make_slab import height_field_mesh  # noqa: E402

BASE = 2.2  # height of the flat top face (the bottom face is at y = 2)
HALF = 1.0  # half side of the face
GRID = 64  # quads per side: 65 x 65 height values, 8192 triangles
# (x, z, amplitude, width): focal lengths 1 / ((n - 1) A / s^2) = 3.8 to 5.3 beyond the 2.2 to the floor,
# so the caustics brighten and darken without folds
BUMPS = [(-0.30, -0.25, 0.012, 0.15), (0.30, -0.20, -0.010, 0.18), (0.05, 0.30, 0.015, 0.20)]

RES = 128  # target image resolution (scene.xml's default)
VIEW = 0.6  # the camera sees [-VIEW, VIEW]^2 of the floor
# radiance of the floor under the flat slab: albedo / pi * irradiance * normal transmittance (1 - 0.04)^2
FLAT_RADIANCE = 0.8 / np.pi * 2.0 * 0.96**2
RING_RADIUS, RING_WIDTH, BACKGROUND = 0.3, 0.04, 0.7  # floor units; the background as a fraction of the flat

DIR = os.path.dirname(os.path.abspath(__file__))


def height_field(bumps):
    """The top face with Gaussian bumps (height_field_mesh of scenes/dpm/make_slab.py)."""
    t = np.linspace(-HALF, HALF, GRID + 1)
    x, z = np.meshgrid(t, t, indexing="xy")
    h = np.zeros_like(x)
    hx, hz = np.zeros_like(x), np.zeros_like(x)
    for cx, cz, a, s in bumps:
        g = a * np.exp(-((x - cx) ** 2 + (z - cz) ** 2) / (2 * s * s))
        h += g
        hx -= g * (x - cx) / (s * s)
        hz -= g * (z - cz) / (s * s)
    return height_field_mesh(x, z, h, hx, hz, BASE)


def ring_image():
    """Radiance per pixel: BACKGROUND + a Gaussian ring, scaled so that its mean is FLAT_RADIANCE."""
    t = (np.arange(RES) + 0.5) / RES * 2 * VIEW - VIEW
    x, z = np.meshgrid(t, t, indexing="xy")
    ring = np.exp(-((np.hypot(x, z) - RING_RADIUS) ** 2) / (2 * RING_WIDTH**2))
    return FLAT_RADIANCE * (BACKGROUND + (1 - BACKGROUND) * ring / ring.mean())


def write_hdr(path, gray):
    """A grey image as an uncompressed Radiance RGBE file (flat scanlines)."""
    m, e = np.frexp(gray)
    mantissa = np.clip(np.floor(m * 256), 0, 255).astype(np.uint8)
    rgbe = np.stack([mantissa, mantissa, mantissa, (e + 128).astype(np.uint8)], axis=-1)
    with open(path, "wb") as out:
        out.write(f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {gray.shape[0]} +X {gray.shape[1]}\n".encode())
        out.write(rgbe.tobytes())


if __name__ == "__main__":
    for name, bumps in (("flat.obj", []), ("bumps.obj", BUMPS)):
        v, n, f = height_field(bumps)
        path = os.path.join(DIR, name)
        write_obj(path, v, n, f, f"top face of a glass slab, height {BASE} + h(x, z) over [-{HALF}, {HALF}]^2, "
                  f"{len(bumps)} Gaussian bumps, {len(f)} triangles (scenes/dpm/image/make_slab.py)")
        print(f"wrote {path}: {len(v)} vertices, {len(f)} triangles")
    write_hdr(os.path.join(DIR, "ring.hdr"), ring_image())
    print(f"wrote {os.path.join(DIR, 'ring.hdr')}: {RES} x {RES}")
