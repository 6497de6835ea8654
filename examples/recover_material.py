#!/usr/bin/env python3
"""Material recovery: a diffuse albedo (RGB) and a roughconductor roughness `alpha` fitted with torch.optim.Adam
to a target image rendered at known true values, through penumbra's reverse mode (render(...).backward()).

    PYTHONPATH=build/python python3 examples/recover_material.py [--quick] [--out DIR]

Prints the relative parameter errors before and after, and writes target.png / initial.png / final.png."""
import argparse
import tempfile
import time
from pathlib import Path

import torch

import penumbra

# A diffuse box on a rough metal floor under two area lights; the one behind, above the frame, shows its
# reflection in the floor, whose spread is the roughness.
SCENE = """<scene version="3.0.0">
  <default name="res" value="64"/>
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0,1.4,4" target="0,0.3,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film></sensor>
  <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
    <bsdf type="roughconductor" id="metal"><string name="material" value="Al"/><float name="alpha" value="0.1"/></bsdf></shape>
  <shape type="cube" id="box"><transform name="to_world"><scale value="0.5"/><rotate y="1" angle="30"/><translate value="-0.7,0.5,0.4"/></transform>
    <bsdf type="diffuse" id="paint"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <shape type="rectangle" id="light"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="35"/><translate value="0.3,2.8,-3"/></transform>
    <emitter type="area"><rgb name="radiance" value="3"/></emitter></shape>
  <shape type="rectangle" id="top"><transform name="to_world"><scale value="1.5"/><rotate x="1" angle="90"/><translate value="0,3,1"/></transform>
    <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
</scene>"""

TRUE = {"paint.reflectance": torch.tensor([0.75, 0.35, 0.15]), "metal.alpha": torch.tensor([0.12])}
INITIAL = {"paint.reflectance": torch.tensor([0.4, 0.4, 0.4]), "metal.alpha": torch.tensor([0.4])}
BOUNDS = {"paint.reflectance": (0.01, 0.99), "metal.alpha": (0.02, 1.0)}


def scene_values(values):
    """The scene's parameters from the optimized ones: penumbra stores alpha as an RGB texture value."""
    return {"paint.reflectance": values["paint.reflectance"], "metal.alpha": values["metal.alpha"].expand(3)}


def relative_errors(values):
    return {k: float((values[k] - TRUE[k]).norm() / TRUE[k].norm()) for k in TRUE}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iterations", type=int, default=120)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=16, help="samples per pixel of each image and gradient")
    ap.add_argument("--lr", type=float, default=0.03)
    ap.add_argument("--out", default=None, help="output directory (default: a new temporary directory)")
    ap.add_argument("--quick", action="store_true", help="reduced size (about a minute on 2 cores)")
    args = ap.parse_args()
    if args.quick:
        args.iterations, args.res, args.spp = 50, 32, 8
    out = Path(args.out or tempfile.mkdtemp(prefix="penumbra_material_"))
    out.mkdir(parents=True, exist_ok=True)
    start = time.time()

    scene = penumbra.load_string(SCENE, res=args.res)
    target = penumbra.render(scene, params=scene_values(TRUE), spp=8 * args.spp, seed=12345)
    penumbra.write_image(out / "target.png", target)

    values = {k: v.clone().requires_grad_() for k, v in INITIAL.items()}
    penumbra.write_image(out / "initial.png", penumbra.render(scene, params=scene_values(values), spp=4 * args.spp, seed=1))
    before = relative_errors(values)
    opt = torch.optim.Adam(values.values(), lr=args.lr)
    # The step size decays to a tenth: late steps average the Monte Carlo noise of the gradients out.
    schedule = torch.optim.lr_scheduler.ExponentialLR(opt, gamma=0.1 ** (1 / args.iterations))
    for it in range(args.iterations):
        opt.zero_grad()
        image = penumbra.render(scene, params=scene_values(values), spp=args.spp, seed=2 * it)
        loss = ((image - target) ** 2).mean()
        loss.backward()
        opt.step()
        schedule.step()
        with torch.no_grad():
            for k, (lo, hi) in BOUNDS.items():
                values[k].clamp_(lo, hi)
        if it % 10 == 0 or it == args.iterations - 1:
            print("iteration %3d  loss %.3e  albedo %s  alpha %.4f" % (
                it, float(loss), [round(float(x), 3) for x in values["paint.reflectance"]],
                float(values["metal.alpha"])))
    after = relative_errors(values)
    penumbra.write_image(out / "final.png", penumbra.render(scene, params=scene_values(values), spp=4 * args.spp, seed=1))
    print("images in %s" % out)
    print("summary: albedo_error %.4f -> %.4f  alpha_error %.4f -> %.4f  seconds %.1f" % (
        before["paint.reflectance"], after["paint.reflectance"], before["metal.alpha"], after["metal.alpha"],
        time.time() - start))


if __name__ == "__main__":
    main()
