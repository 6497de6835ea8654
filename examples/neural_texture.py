#!/usr/bin/env python3
"""Neural texture: a tiny MLP (Fourier features of (u, v) -> 2 x 32 hidden -> RGB sigmoid) gives the texels of
a `bitmap` texture's `data`, fitted through the renderer to an image of the same scene textured with a
procedural checkerboard. Each step passes the MLP's output as params={"tex.data": texels}; penumbra's reverse
mode gives d loss / d texels and torch carries it on into the MLP's weights.

    PYTHONPATH=build/python python3 examples/neural_texture.py [--quick] [--out DIR]

Prints the image loss and the texture error before and after, and writes target.png / initial.png /
final.png (renders) and texture_target.png / texture_initial.png / texture_final.png."""
import argparse
import math
import tempfile
import time
from pathlib import Path

import torch

import penumbra

# A textured square tilted toward the camera, lit by an area light and a dim sky; `$texture` is its image.
SCENE = """<scene version="3.0.0">
  <default name="res" value="64"/>
  <default name="texture" value="initial.exr"/>
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="0,1.2,3.4" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film></sensor>
  <shape type="rectangle" id="board"><transform name="to_world"><rotate x="1" angle="-60"/></transform>
    <bsdf type="diffuse" id="paint"><texture type="bitmap" name="reflectance" id="tex">
      <string name="filename" value="$texture"/></texture></bsdf></shape>
  <shape type="rectangle" id="light"><transform name="to_world"><rotate x="1" angle="60"/><translate value="0.5,2.5,2"/></transform>
    <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>
  <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
</scene>"""


def checkerboard(size, squares=4):
    """The target texture: a squares x squares checkerboard of orange and teal."""
    i = torch.arange(size) * squares // size
    odd = ((i[:, None] + i[None, :]) % 2).float()[..., None]
    return odd * torch.tensor([0.9, 0.5, 0.1]) + (1 - odd) * torch.tensor([0.1, 0.6, 0.7])


class FourierMLP(torch.nn.Module):
    """(u, v) -> [sin, cos](2π 2^k (u, v)), k < frequencies -> 32 -> 32 -> RGB in (0, 1) (Tancik et al. 2020)."""

    def __init__(self, frequencies=4, hidden=32):
        super().__init__()
        self.scales = 2 * math.pi * 2.0 ** torch.arange(frequencies)
        self.net = torch.nn.Sequential(torch.nn.Linear(4 * frequencies, hidden), torch.nn.ReLU(),
                                       torch.nn.Linear(hidden, hidden), torch.nn.ReLU(),
                                       torch.nn.Linear(hidden, 3), torch.nn.Sigmoid())

    def forward(self, uv):
        angles = (uv[..., None] * self.scales).flatten(-2)
        return self.net(torch.cat([torch.sin(angles), torch.cos(angles)], -1))


def texel_centers(size):
    """(u, v) of the texel centers of a size x size image (row 0 at v = 0, as the bitmap reads it)."""
    c = (torch.arange(size) + 0.5) / size
    v, u = torch.meshgrid(c, c, indexing="ij")
    return torch.stack([u, v], -1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iterations", type=int, default=300)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=8, help="samples per pixel of each image and gradient")
    ap.add_argument("--texture", type=int, default=32, help="texture width and height (texels)")
    ap.add_argument("--lr", type=float, default=0.01)
    ap.add_argument("--out", default=None, help="output directory (default: a new temporary directory)")
    ap.add_argument("--quick", action="store_true", help="reduced size (about a minute on 2 cores)")
    args = ap.parse_args()
    if args.quick:
        args.iterations, args.res, args.spp, args.texture = 120, 32, 4, 16
    out = Path(args.out or tempfile.mkdtemp(prefix="penumbra_texture_"))
    out.mkdir(parents=True, exist_ok=True)
    start = time.time()
    torch.manual_seed(0)

    target_texture = checkerboard(args.texture)
    penumbra.write_image(out / "target.exr", target_texture)
    target = penumbra.render(penumbra.load_string(SCENE, out, res=args.res, texture="target.exr"), spp=8 * args.spp,
                             seed=1000)

    mlp = FourierMLP()
    uv = texel_centers(args.texture)
    with torch.no_grad():
        penumbra.write_image(out / "initial.exr", mlp(uv))
    scene = penumbra.load_string(SCENE, out, res=args.res)

    def evaluate():
        with torch.no_grad():
            texels = mlp(uv)
            image = penumbra.render(scene, params={"tex.data": texels}, spp=4 * args.spp, seed=1)
            return texels, image, float(((image - target) ** 2).mean()), float((texels - target_texture).abs().mean())

    texels0, image0, loss_before, error_before = evaluate()
    opt = torch.optim.Adam(mlp.parameters(), lr=args.lr)
    for it in range(args.iterations):
        opt.zero_grad()
        image = penumbra.render(scene, params={"tex.data": mlp(uv)}, spp=args.spp, seed=2 * it)
        loss = ((image - target) ** 2).mean()
        loss.backward()
        opt.step()
        if it % 20 == 0 or it == args.iterations - 1:
            print("iteration %3d  loss %.3e" % (it, float(loss)))
    texels, image, loss_after, error_after = evaluate()
    for name, picture in [("target", target), ("initial", image0), ("final", image),
                          ("texture_target", target_texture), ("texture_initial", texels0), ("texture_final", texels)]:
        penumbra.write_image(out / (name + ".png"), picture)
    print("images in %s" % out)
    print("summary: image_loss %.4e -> %.4e  texture_error %.4f -> %.4f  seconds %.1f" % (
        loss_before, loss_after, error_before, error_after, time.time() - start))


if __name__ == "__main__":
    main()
