"""`pip install --no-build-isolation .` (pyproject.toml + setup.py driving CMake) installs an importable package.
The extension comes from the already configured build (PENUMBRA_CMAKE_BUILD_DIR) so the test takes seconds; a
fresh `pip install` configures its own build the same way."""
import os
import subprocess
import sys

from conftest import SOURCE


def test_pip_install_gives_an_importable_package(tmp_path):
    build = os.environ.get("PENUMBRA_BUILD_DIR", str(SOURCE / "build"))
    env = dict(os.environ, PENUMBRA_CMAKE_BUILD_DIR=build, PIP_NO_INDEX="1")
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--quiet",
                        "--target", str(tmp_path / "site"), str(SOURCE)], capture_output=True, text=True, env=env,
                       timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    check = ("import penumbra, os; assert os.path.dirname(penumbra.__file__).startswith(%r); "
             "s = penumbra.load_file(%r); print(tuple(penumbra.render(s, spp=1).shape))"
             % (str(tmp_path / "site"), str(SOURCE / "scenes" / "cbox" / "cbox.xml")))
    env = dict(os.environ, PYTHONPATH=str(tmp_path / "site"))
    r = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "(256, 256, 3)"
