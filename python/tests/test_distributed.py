"""Scale-out with torch.distributed: 2 local ranks (gloo) take the same steps as one process with the same seeds,
up to the order of the gradient sum."""
import json
import os
import socket
import subprocess
import sys

import numpy as np

from conftest import SOURCE, run_example


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_ranks_equal_one_process(tmp_path):
    run_example("distributed_views.py", "--quick", "--out", str(tmp_path / "one.json"))
    r = subprocess.run([sys.executable, "-m", "penumbra.torchrun", "--nproc_per_node=2",
                        "--master_port=%d" % free_port(), str(SOURCE / "examples" / "distributed_views.py"),
                        "--quick", "--out", str(tmp_path / "two.json")],
                       capture_output=True, text=True, timeout=600, env=dict(os.environ))
    assert r.returncode == 0, r.stdout + r.stderr
    one = json.loads((tmp_path / "one.json").read_text())
    two = json.loads((tmp_path / "two.json").read_text())
    assert one["world_size"] == 1 and two["world_size"] == 2
    for name, values in one["parameters"].items():
        np.testing.assert_allclose(two["parameters"][name], values, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(two["loss"], one["loss"], rtol=1e-5)
    # The parameters moved toward the truth (the run is not a no-op).
    assert one["errors"]["white.reflectance"] < 0.8 * one["initial_errors"]["white.reflectance"]
