"""Shared pieces of the Python tests: small scenes and paths."""
import os
import sys
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("PENUMBRA_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CLI = os.environ.get("PENUMBRA_CLI", str(SOURCE / "build" / "penumbra"))

# A diffuse box on a rough metal floor under an area light; two sensors (front 24x16, side 16x16).
BOX_SCENE = """<scene version="3.0.0">
  <default name="res" value="24"/>
  <sensor type="perspective" id="front"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,1.6,4" target="0,0.35,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="16"/></film></sensor>
  <sensor type="perspective" id="side"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="4,1.6,0" target="0,0.35,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
  <shape type="rectangle" id="floor"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
    <bsdf type="roughconductor" id="metal"><float name="alpha" value="0.3"/></bsdf></shape>
  <shape type="cube" id="box"><transform name="to_world"><scale value="0.4"/><translate value="0,0.4,0"/></transform>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7,0.6,0.5"/></bsdf></shape>
  <shape type="rectangle" id="light"><transform name="to_world"><rotate x="1" angle="90"/><translate value="0,3,0"/></transform>
    <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
</scene>"""


@pytest.fixture
def box_scene():
    import penumbra
    return penumbra.load_string(BOX_SCENE)


def run_example(name, *args, env=None):
    """Runs examples/<name> with the test interpreter; returns its stdout (fails the test on a non-zero exit)."""
    import subprocess
    e = dict(os.environ)
    e.update(env or {})
    r = subprocess.run([sys.executable, str(SOURCE / "examples" / name), *args], capture_output=True, text=True,
                       env=e, timeout=600)
    assert r.returncode == 0, "%s failed:\n%s\n%s" % (name, r.stdout, r.stderr)
    return r.stdout
