#!/usr/bin/env python3
"""Writes the meshes of the multi-view shape-optimization demo (scenes/multiview/, docs/optimize.md):

  sphere_<n>.ply  the initial shape: a geodesic sphere of radius 0.8 (the icosahedron's faces split n x n,
                  projected onto the sphere), 10 n^2 + 2 vertices, 20 n^2 triangles
  blob_<n>.ply    the target: the same vertices moved radially, r(d) = 0.8 (1 + b(d)), b a sum of smooth bumps
                  (see blob_radius), so that vertex i of both files is the same point of the surface and the
                  mean vertex error is defined; the same connectivity

The demo uses n = 45 (20,252 vertices), the test (tests/test_optimize_multiview.cpp) n = 16 (2,562 vertices).
Binary little-endian PLY without normals (the loader computes smooth normals, recomputed whenever
vertex_positions change). Pure Python; run from anywhere:
    python3 scripts/make_multiview_meshes.py           # n = 45 and n = 16
    python3 scripts/make_multiview_meshes.py 24        # only n = 24
"""
import math
import os
import struct
import sys

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "multiview")
RADIUS = 0.8


def icosahedron():
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
         (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return v, f


def normalize(p):
    n = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
    return (p[0] / n, p[1] / n, p[2] / n)


def geodesic_sphere(n):
    """Unit directions and triangles: each icosahedron face split into n^2 triangles, shared vertices merged
    (keyed by their integer barycentric coordinates on the shared edges and corners)."""
    corners, faces = icosahedron()
    index, dirs, tris = {}, [], []

    def vertex(face, i, j):
        a, b, c = faces[face]
        k = n - i - j
        # Weights of the corners a, b, c; the key names a point by its corners and weights, order-free.
        key = tuple(sorted(((a, k), (b, i), (c, j))))
        key = tuple(w for w in key if w[1] > 0)
        if key not in index:
            p = tuple((k * corners[a][d] + i * corners[b][d] + j * corners[c][d]) / n for d in range(3))
            index[key] = len(dirs)
            dirs.append(normalize(p))
        return index[key]

    for face in range(len(faces)):
        for i in range(n):
            for j in range(n - i):
                tris.append((vertex(face, i, j), vertex(face, i + 1, j), vertex(face, i, j + 1)))
                if i + j < n - 1:
                    tris.append((vertex(face, i + 1, j), vertex(face, i + 1, j + 1), vertex(face, i, j + 1)))
    return dirs, tris


def blob_radius(d):
    """b(d): two broad lobes and a gentle ridge, |b| <= ~0.3, smooth (low-frequency) so that a smooth
    parameterization can reach it from the sphere."""
    x, y, z = d
    lobes = 0.3 * math.exp(-8.0 * ((x - 0.6) ** 2 + (y - 0.5) ** 2 + (z - 0.6) ** 2)) + 0.25 * math.exp(
        -6.0 * ((x + 0.7) ** 2 + (y + 0.2) ** 2 + (z - 0.3) ** 2))
    dent = -0.2 * math.exp(-7.0 * ((x - 0.1) ** 2 + (y + 0.9) ** 2 + (z + 0.4) ** 2))
    ridge = 0.06 * math.sin(3.0 * x) * math.cos(2.0 * z)
    return lobes + dent + ridge


def write_ply(path, points, tris):
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                 "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(points), len(tris))).encode("ascii"))
        for p in points:
            f.write(struct.pack("<3f", *p))
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))


def main():
    sizes = [int(a) for a in sys.argv[1:]] or [45, 16]
    os.makedirs(OUT, exist_ok=True)
    for n in sizes:
        dirs, tris = geodesic_sphere(n)
        sphere = [tuple(RADIUS * c for c in d) for d in dirs]
        blob = [tuple(RADIUS * (1.0 + blob_radius(d)) * c for c in d) for d in dirs]
        write_ply(os.path.join(OUT, "sphere_%d.ply" % n), sphere, tris)
        write_ply(os.path.join(OUT, "blob_%d.ply" % n), blob, tris)
        print("n = %d: %d vertices, %d triangles" % (n, len(dirs), len(tris)))


if __name__ == "__main__":
    main()
