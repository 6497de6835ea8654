"""Multi-view inverse rendering spread over processes with torch.distributed (gloo backend, CPU).

Recovers a box's albedo and a metal floor's roughness from V views (V sensors in one scene). Each rank renders
the views v with v % world_size == rank, back-propagates its share of the loss, and the gradients are summed
with all_reduce, so every rank takes the same Adam step and holds the same parameters. The samples of a view
depend only on (iteration, view), not on the rank: the result equals the single-process run up to the order of
the gradient sum.

    python3 examples/distributed_views.py                              # one process
    torchrun --nproc_per_node=2 examples/distributed_views.py          # two ranks on this machine
    # several machines (same command on each, node_rank 0..N-1; the first node's address as the endpoint):
    torchrun --nnodes=2 --nproc_per_node=1 --node_rank=0 --rdzv_backend=c10d \\
             --rdzv_endpoint=HOST0:29500 examples/distributed_views.py

Threads: each rank renders with cores / (ranks on this machine) threads (--threads overrides), so ranks on one
machine do not oversubscribe its cores.
"""
import argparse
import json
import math
import os
import tempfile
import time

import torch
import torch.distributed as dist

import penumbra

ALBEDO, ALPHA = "white.reflectance", "metal.alpha"
TRUTH = {ALBEDO: torch.tensor([0.75, 0.35, 0.2]), ALPHA: torch.tensor([0.12, 0.12, 0.12])}
INIT = {ALBEDO: torch.tensor([0.4, 0.4, 0.4]), ALPHA: torch.tensor([0.35, 0.35, 0.35])}


def scene_xml(views, res):
    sensors = []
    for v in range(views):
        a = 2 * math.pi * v / views
        sensors.append(f"""<sensor type="perspective" id="view{v}"><float name="fov" value="35"/>
      <transform name="to_world"><lookat origin="{4 * math.sin(a):.4f},1.8,{4 * math.cos(a):.4f}" target="0,0.3,0" up="0,1,0"/></transform>
      <film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/></film></sensor>""")
    return f"""<scene version="3.0.0">
  {"".join(sensors)}
  <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
    <bsdf type="roughconductor" id="metal"><float name="alpha" value="0.2"/></bsdf></shape>
  <shape type="cube" id="box"><transform name="to_world"><scale value="0.4"/><translate value="0,0.4,0"/></transform>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.5"/></bsdf></shape>
  <shape type="rectangle" id="light"><transform name="to_world"><scale value="1.5"/><rotate x="1" angle="90"/><translate value="0.5,3,0.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>
</scene>"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--views", type=int, default=8)
    parser.add_argument("--res", type=int, default=48)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--iterations", type=int, default=60)
    parser.add_argument("--lr", type=float, default=0.03)
    parser.add_argument("--threads", type=int, default=0, help="threads per rank (0: cores / local ranks)")
    parser.add_argument("--quick", action="store_true", help="a reduced run (the tests use it)")
    parser.add_argument("--out", default="", help="write the result as JSON here (rank 0)")
    args = parser.parse_args()
    if args.quick:
        args.views, args.res, args.spp, args.iterations = 4, 16, 4, 6

    distributed = "RANK" in os.environ  # set by torchrun
    if distributed:
        dist.init_process_group("gloo")
    rank, world = (dist.get_rank(), dist.get_world_size()) if distributed else (0, 1)
    local = int(os.environ.get("LOCAL_WORLD_SIZE", "1"))
    threads = args.threads or max(1, (os.cpu_count() or 1) // local)
    penumbra.set_thread_count(threads)
    torch.set_num_threads(threads)

    scene = penumbra.load_string(scene_xml(args.views, args.res))
    mine = [v for v in range(args.views) if v % world == rank]
    targets = {v: penumbra.render(scene, params=TRUTH, spp=4 * args.spp, seed=10_000 + v, sensor=v) for v in mine}

    theta = {k: v.clone().requires_grad_() for k, v in INIT.items()}
    optimizer = torch.optim.Adam(theta.values(), lr=args.lr)
    history = []
    start = time.perf_counter()
    for it in range(args.iterations):
        optimizer.zero_grad()
        loss = torch.zeros(())
        for v in mine:
            seed = it * args.views + v
            image = penumbra.render(scene, params=theta, spp=args.spp, seed=2 * seed, seed_grad=2 * seed + 1,
                                    sensor=v)
            view_loss = ((image - targets[v]) ** 2).mean() / args.views
            view_loss.backward()
            loss += view_loss.detach()
        if distributed:
            for t in theta.values():
                dist.all_reduce(t.grad, op=dist.ReduceOp.SUM)
            dist.all_reduce(loss, op=dist.ReduceOp.SUM)
        optimizer.step()
        with torch.no_grad():
            theta[ALPHA].clamp_(0.01, 1.0)
            theta[ALBEDO].clamp_(0.0, 1.0)
        history.append(float(loss))
    seconds = time.perf_counter() - start

    errors = {k: float((theta[k] - TRUTH[k]).norm() / TRUTH[k].norm()) for k in theta}
    initial = {k: float((INIT[k] - TRUTH[k]).norm() / TRUTH[k].norm()) for k in theta}
    if rank == 0:
        print("ranks %d x %d threads: %d views, %d iterations in %.2f s; loss %.4g -> %.4g; relative error "
              "albedo %.3f -> %.3f, alpha %.3f -> %.3f" % (world, threads, args.views, args.iterations, seconds,
                                                          history[0], history[-1], initial[ALBEDO], errors[ALBEDO],
                                                          initial[ALPHA], errors[ALPHA]))
        if args.out:
            with open(args.out + ".tmp", "w") as f:
                json.dump({"world_size": world, "threads": threads, "seconds": seconds, "loss": history,
                           "parameters": {k: t.detach().tolist() for k, t in theta.items()}, "errors": errors,
                           "initial_errors": initial}, f, indent=1)
            os.replace(args.out + ".tmp", args.out)
    if distributed:
        dist.destroy_process_group()


if __name__ == "__main__":
    main()
