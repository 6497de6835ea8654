#!/usr/bin/env python3
"""penumbra's Sinkhorn (src/core/sinkhorn.h) against POT (Debian's python3-pot) on the DPM-G matching problem:
all pixels of an N x N rendering matched to all pixels of an N x N target as 5-D points (RGB + xy), with the
cost C = 1/2 |x - y|^2 and eps = blur^2 (the images of bench/bench_sinkhorn.cpp).

  1. Agreement: the transport plan and the matching of both at 16^2, same eps, both converged.
  2. Time per Sinkhorn iteration at blur 0.01 (the paper's) for N = 32, 64, 128 on 1 and 2 threads, and the
     peak memory of the process (POT needs the dense N^4 cost matrix; penumbra computes costs on the fly).
  3. The full annealed solve of the paper's setup (GeomLoss: scaling 0.9, one iteration at the final eps).

Each measurement runs in its own process (thread counts of numpy's BLAS are fixed at import; peak memory is per
process). Usage, from the repository root after building:
  PYTHONPATH=build/python /usr/bin/python3 scripts/compare_sinkhorn_pot.py [--sizes 32 64 128] [--threads 1 2]
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time
import warnings

import numpy as np


def blob_image(n, cx, cy, sigma, rgb):
    """An n x n image as 5-D points: background (0.2u, 0.2v, 0.1) plus a Gaussian blob of colour rgb."""
    v, u = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n, indexing="ij")
    k = np.exp(-((u - cx) ** 2 + (v - cy) ** 2) / (2 * sigma * sigma))
    p = np.stack([0.2 * u + rgb[0] * k, 0.2 * v + rgb[1] * k, 0.1 + rgb[2] * k, u, v], axis=-1)
    return p.reshape(-1, 5)


def problem(n):
    x = blob_image(n, 0.35, 0.40, 0.08, (0.9, 0.7, 0.2))
    y = blob_image(n, 0.62, 0.58, 0.06, (0.8, 0.8, 0.3))
    return x, np.ones(n * n), y, np.ones(n * n)


def native():
    """The extension module alone (build/python/penumbra/_penumbra*.so), without torch."""
    for root in os.environ.get("PYTHONPATH", "build/python").split(os.pathsep):
        sys.path.insert(0, os.path.join(root, "penumbra"))
    import _penumbra
    return _penumbra


def cost_matrix(x, y):
    import ot
    return 0.5 * ot.dist(x, y, metric="sqeuclidean")


def peak_rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def timed(run, n):
    """The shortest of (64/n)^2 runs (at least one): small sizes are repeated against the noise of a shared CPU."""
    best = float("inf")
    for _ in range(max(1, (64 // n) ** 2)):
        t0 = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - t0)
    return best


def iterations(n):
    """Iterations of the longer timed run (the shorter has one): POT checks the marginal at iteration 0 only, below
    10, so their time difference is that of pure iterations for both solvers."""
    return 10 if n <= 64 else 4


def worker(kind, n, threads):
    """One measurement in this process; prints a JSON line."""
    x, a, y, b = problem(n)
    eps = 0.01**2
    out = {"kind": kind, "n": n, "threads": threads}
    if kind == "cpp_iteration":
        pen = native()
        t = [timed(lambda: pen.sinkhorn(x, a, y, b, blur=0.01, scaling=0, tolerance=0, max_iterations=k,
                                        threads=threads), n) for k in (1, iterations(n))]
        out["seconds_per_iteration"] = (t[1] - t[0]) / (iterations(n) - 1)
    elif kind == "cpp_annealed":
        pen = native()
        t0 = time.perf_counter()
        r = pen.sinkhorn(x, a, y, b, blur=0.01, scaling=0.9, max_iterations=1, threads=threads)
        out["seconds"] = time.perf_counter() - t0
        out["iterations"] = r["annealing_steps"] + r["iterations"]
        out["marginal_error"] = r["marginal_error"]
    elif kind in ("pot_sinkhorn_log", "pot_sinkhorn"):
        import ot
        t0 = time.perf_counter()
        m = cost_matrix(x, y)
        out["seconds_cost_matrix"] = time.perf_counter() - t0
        a, b = a / a.sum(), b / b.sum()
        solve = ot.bregman.sinkhorn_log if kind == "pot_sinkhorn_log" else ot.bregman.sinkhorn_knopp
        with np.errstate(all="ignore"), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            t = [timed(lambda: solve(a, b, m, eps, numItermax=k, stopThr=0), n) for k in (1, iterations(n))]
            plan = solve(a, b, m, eps, numItermax=3, stopThr=0)
        out["seconds_per_iteration"] = (t[1] - t[0]) / (iterations(n) - 1)
        out["warnings"] = sorted({str(w.message).splitlines()[0] for w in caught})
        out["finite"] = bool(np.isfinite(plan).all() and plan.sum() > 0)
    elif kind == "pot_emd":
        import ot
        m = cost_matrix(x, y)
        t0 = time.perf_counter()
        ot.emd(a / a.sum(), b / b.sum(), m, numItermax=10**8)
        out["seconds"] = time.perf_counter() - t0
    out["peak_rss_gb"] = peak_rss_gb()
    out["load_average"] = os.getloadavg()[0]
    print(json.dumps(out))


def measure(kind, n, threads, timeout):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads),
               MKL_NUM_THREADS=str(threads))
    cmd = [sys.executable, __file__, "--worker", kind, str(n), str(threads)]
    try:
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"kind": kind, "n": n, "threads": threads, "failed": f"over {timeout} s"}
    if done.returncode != 0:
        return {"kind": kind, "n": n, "threads": threads,
                "failed": (done.stderr.strip().splitlines() or [f"exit {done.returncode}"])[-1]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def agreement(n=16, blur=0.05):
    """Both solvers converged at the same eps: plans and barycentric matches."""
    import ot
    pen = native()
    x, a, y, b = problem(n)
    r = pen.sinkhorn(x, a, y, b, blur=blur, scaling=0.9, tolerance=2e-8, max_iterations=100000, threads=1,
                     plan=True)
    p_pot, log = ot.bregman.sinkhorn_log(a / a.sum(), b / b.sum(), cost_matrix(x, y), blur**2,
                                         numItermax=100000, stopThr=1e-12, log=True)
    p_cpp = r["plan"]
    match_pot = (p_pot @ y) / p_pot.sum(1)[:, None]
    return {
        "n": n, "blur": blur, "eps": blur**2,
        "cpp_iterations": r["annealing_steps"] + r["iterations"], "cpp_marginal_error_l1": r["marginal_error"],
        "pot_iterations": len(log["err"]) * 10, "pot_marginal_error_l2": float(log["err"][-1]),
        "plan_l1_difference": float(np.abs(p_cpp - p_pot).sum()),
        "plan_max_difference_over_max": float(np.abs(p_cpp - p_pot).max() / p_pot.max()),
        "match_max_difference": float(np.abs(r["matched"] - match_pot).max()),
        "match_max_displacement": float(np.abs(match_pot - x).max()),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--timeout", type=float, default=1800)
    parser.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker[0], int(args.worker[1]), int(args.worker[2]))
        return
    print(json.dumps({"agreement": agreement()}), flush=True)
    for n in args.sizes:
        for threads in args.threads:
            for kind in ("cpp_iteration", "pot_sinkhorn_log", "pot_sinkhorn", "cpp_annealed"):
                print(json.dumps(measure(kind, n, threads, args.timeout)), flush=True)
        if n <= 64:
            print(json.dumps(measure("pot_emd", n, 1, args.timeout)), flush=True)


if __name__ == "__main__":
    main()
