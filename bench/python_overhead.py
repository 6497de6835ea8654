"""The cost of the Python path against the command line, measured in one run on the same scene, samples and seed:
the render and the reverse-mode gradient as the CLI reports their time (inside the process, scene loaded) and as
seen from Python (penumbra.render, and its backward through torch autograd). Prints the ratios.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--scene scenes/cbox/cbox.xml] [--spp 32]
"""
import argparse
import json
import re
import subprocess
import tempfile
import time
from pathlib import Path

import torch

import penumbra

ROOT = Path(__file__).resolve().parents[1]


def best_of(n, fn):
    times = []
    for _ in range(n):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default=str(ROOT / "scenes" / "cbox" / "cbox.xml"))
    p.add_argument("--cli", default=str(ROOT / "build" / "penumbra"))
    p.add_argument("--param", default="white.reflectance")
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--method", default="interior")
    p.add_argument("--repeat", type=int, default=5)
    a = p.parse_args()
    tmp = Path(tempfile.mkdtemp())

    scene = penumbra.load_file(a.scene)
    theta = scene.params()[a.param].clone().requires_grad_()
    adjoint = torch.ones_like(penumbra.render(scene, spp=1)) / 1000
    penumbra.write_image(tmp / "adjoint.exr", adjoint)

    py_render = best_of(a.repeat, lambda: penumbra.render(scene, spp=a.spp, seed=1))
    image = penumbra.render(scene, params={a.param: theta}, spp=a.spp, seed=1, seed_grad=2, method=a.method)

    def backward():
        image.backward(adjoint, retain_graph=True)
    py_gradient = best_of(a.repeat, backward)

    def cli_seconds(args, pattern):
        best = float("inf")
        for _ in range(a.repeat):
            out = subprocess.run([a.cli, *args, "-q"], capture_output=True, text=True, check=True)
            best = min(best, float(re.search(pattern, out.stderr).group(1)))
        return best
    cli_render = cli_seconds(["render", a.scene, "--spp", str(a.spp), "--seed", "1", "-o", str(tmp / "r.exr")],
                             r"in ([0-9.]+) s")
    cli_gradient = cli_seconds(["gradient", a.scene, "--adjoint", str(tmp / "adjoint.exr"), "--param", a.param,
                                "--spp", str(a.spp), "--seed", "2", "--method", a.method, "-o", str(tmp / "g.json")],
                               r"in ([0-9.]+) s")
    print("%-34s %10s %10s %8s" % ("%s, %d spp, %s" % (Path(a.scene).name, a.spp, a.method), "CLI s", "Python s",
                                   "ratio"))
    print("%-34s %10.3f %10.3f %8.3f" % ("render", cli_render, py_render, py_render / cli_render))
    print("%-34s %10.3f %10.3f %8.3f" % ("gradient (reverse mode)", cli_gradient, py_gradient,
                                          py_gradient / cli_gradient))


if __name__ == "__main__":
    main()
