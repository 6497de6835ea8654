#!/usr/bin/env python3
"""Multi-view mesh recovery: an icosphere deformed into a target ellipsoid from images of several views, by
optimizing `<shape>.vertex_positions` through penumbra's psdr method (whose boundary terms make silhouettes
move the vertices), with the Laplacian-preconditioned parameterization of Nicolet et al. 2021, "Large Steps in
Inverse Rendering of Geometry": u = (I + λL) x, Adam on u, x = (I + λL)⁻¹ u.

    PYTHONPATH=build/python python3 examples/multiview_mesh.py [--quick] [--out DIR]

Prints the mean radial distance of the vertices to the target surface before and after, and writes
target_<view>.png / initial_<view>.png / final_<view>.png."""
import argparse
import tempfile
import time
from pathlib import Path

import torch

import penumbra

AXES = torch.tensor([1.0, 0.6, 0.8])  # the target ellipsoid's semi-axes; the initial sphere has radius 0.8
RADIUS = 0.8
VIEWS = [("front", "0,0.8,3.2"), ("right", "3.2,0.8,0"), ("back", "-1.6,1.4,-2.8"), ("top", "0.5,3.3,0.4")]


def scene_xml(res):
    """A diffuse mesh (file `$mesh`) under a sun and a sky, seen by one sensor per view."""
    sensors = "".join("""
  <sensor type="perspective" id="%s"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="%s" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/></film></sensor>"""
                      % (name, origin, res, res) for name, origin in VIEWS)
    return """<scene version="3.0.0">
  <default name="mesh" value="initial.obj"/>
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>%s
  <shape type="obj" id="blob"><string name="filename" value="$mesh"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8,0.5,0.3"/></bsdf></shape>
  <emitter type="directional"><vector name="direction" value="-1,-2,-0.7"/><rgb name="irradiance" value="3"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>
</scene>""" % sensors


def icosphere(subdivisions):
    """A unit icosphere: the icosahedron's faces split in four `subdivisions` times, vertices on the sphere."""
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [torch.tensor(v, dtype=torch.float64) for v in verts]
    for _ in range(subdivisions):
        midpoint, split = {}, []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                midpoint[key] = len(verts)
                verts.append((verts[a] + verts[b]) / 2)
            return midpoint[key]

        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    v = torch.stack(verts)
    return (v / v.norm(dim=1, keepdim=True)).float(), torch.tensor(faces)


def write_obj(path, verts, faces):
    lines = ["v %.6f %.6f %.6f" % tuple(p) for p in verts.tolist()]
    lines += ["f %d %d %d" % tuple(i + 1 for i in f) for f in faces.tolist()]
    Path(path).write_text("\n".join(lines) + "\n")


def uniform_laplacian(n, faces):
    """L = D − A of the mesh's edge graph (Nicolet et al. 2021, Sec. 4: the combinatorial Laplacian)."""
    edges = torch.cat([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    adjacency = torch.zeros(n, n)
    adjacency[edges[:, 0], edges[:, 1]] = 1
    adjacency[edges[:, 1], edges[:, 0]] = 1
    return torch.diag(adjacency.sum(1)) - adjacency


def distance_to_target(x):
    """Mean radial distance to the ellipsoid |p / AXES| = 1: | |p| − r(p̂) | with r(p̂) = 1 / |p̂ / AXES|."""
    r = x.norm(dim=1)
    return float((r - 1 / (x / r[:, None] / AXES).norm(dim=1)).abs().mean())


def render_views(scene, params, spp, seed):
    return [penumbra.render(scene, params=params, spp=spp, seed=seed + 7 * i, sensor=i) for i in range(len(VIEWS))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iterations", type=int, default=150)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=8, help="samples per pixel of each image and gradient")
    ap.add_argument("--subdivisions", type=int, default=2, help="icosphere subdivisions (2: 162, 3: 642 vertices)")
    ap.add_argument("--lam", type=float, default=10.0, help="λ of the preconditioner I + λL")
    ap.add_argument("--lr", type=float, default=0.05)
    ap.add_argument("--out", default=None, help="output directory (default: a new temporary directory)")
    ap.add_argument("--quick", action="store_true", help="reduced size (about a minute on 2 cores)")
    args = ap.parse_args()
    if args.quick:
        args.iterations, args.res, args.spp, args.subdivisions = 40, 32, 4, 2
    out = Path(args.out or tempfile.mkdtemp(prefix="penumbra_mesh_"))
    out.mkdir(parents=True, exist_ok=True)
    start = time.time()

    sphere, faces = icosphere(args.subdivisions)
    write_obj(out / "initial.obj", RADIUS * sphere, faces)
    write_obj(out / "target.obj", sphere * AXES, faces)
    xml = scene_xml(args.res)
    targets = render_views(penumbra.load_string(xml, out, mesh="target.obj"), None, 8 * args.spp, 1000)
    scene = penumbra.load_string(xml, out)
    x0 = scene.params()["blob.vertex_positions"]
    faces = scene.faces("blob")  # the loader's vertex order (it numbers vertices in order of first use)

    M = torch.eye(len(x0)) + args.lam * uniform_laplacian(len(x0), faces)
    cholesky = torch.linalg.cholesky(M)
    u = (M @ x0).requires_grad_()
    opt = torch.optim.Adam([u], lr=args.lr)
    before = distance_to_target(x0)
    for it in range(args.iterations):
        opt.zero_grad()
        x = torch.cholesky_solve(u, cholesky)
        images = render_views(scene, {"blob.vertex_positions": x}, args.spp, 2 * len(VIEWS) * it)
        loss = sum(((image - target) ** 2).mean() for image, target in zip(images, targets))
        loss.backward()
        opt.step()
        if it % 10 == 0 or it == args.iterations - 1:
            print("iteration %3d  loss %.3e  distance %.4f" % (it, float(loss), distance_to_target(x.detach())))
    x = torch.cholesky_solve(u.detach(), cholesky)
    after = distance_to_target(x)
    write_obj(out / "final.obj", x, faces)
    for (name, _), target, first, last in zip(VIEWS, targets, render_views(scene, {"blob.vertex_positions": x0},
                                                                          4 * args.spp, 1),
                                             render_views(scene, {"blob.vertex_positions": x}, 4 * args.spp, 1)):
        penumbra.write_image(out / ("target_%s.png" % name), target)
        penumbra.write_image(out / ("initial_%s.png" % name), first)
        penumbra.write_image(out / ("final_%s.png" % name), last)
    print("images and meshes in %s" % out)
    print("summary: vertices %d  views %d  distance %.4f -> %.4f  seconds %.1f" % (
        len(x0), len(VIEWS), before, after, time.time() - start))


if __name__ == "__main__":
    main()
