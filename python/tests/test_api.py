"""The Python API: loading, parameters, rendering, errors, determinism."""
import numpy as np
import pytest
import torch

import penumbra
from conftest import BOX_SCENE, SOURCE


def test_load_file_and_render_cbox():
    scene = penumbra.load_file(SOURCE / "scenes" / "cbox" / "cbox.xml")
    image = penumbra.render(scene, spp=2, seed=3)
    assert isinstance(image, torch.Tensor) and image.dtype == torch.float32
    w, h = scene.sensors()[0][1:]
    assert tuple(image.shape) == (h, w, 3)
    assert image.mean() > 0


def test_defines_override_defaults():
    scene = penumbra.load_string(BOX_SCENE, res=12)
    assert scene.sensors()[0] == ("front", 12, 16)


def test_params_are_named_like_the_cli(box_scene):
    params = box_scene.params()
    names = list(params.keys())
    for name in ["white.reflectance.value", "metal.alpha.value", "box.vertex_positions", "box.translate",
                 "box.rotate", "box.scale", "front.translate", "front.rotate"]:
        assert name in names, name
    assert tuple(params["white.reflectance.value"].shape) == (3,)
    assert params["box.vertex_positions"].shape[1] == 3
    assert torch.equal(params["box.translate"], torch.zeros(3))
    assert torch.allclose(params["white.reflectance"], torch.tensor([0.7, 0.6, 0.5]))  # alias without .value


def test_update_round_trip_changes_the_image(box_scene):
    params = box_scene.params()
    before = penumbra.render(box_scene, spp=4, seed=1)
    params["white.reflectance"] = torch.tensor([0.1, 0.2, 0.3])
    params.update()
    assert torch.allclose(box_scene.params()["white.reflectance"], torch.tensor([0.1, 0.2, 0.3]))
    after = penumbra.render(box_scene, spp=4, seed=1)
    assert not torch.equal(before, after)
    params.update({"white.reflectance": torch.tensor([0.7, 0.6, 0.5])})
    assert torch.equal(penumbra.render(box_scene, spp=4, seed=1), before)


def test_same_seed_same_image_whatever_the_threads(box_scene):
    a = penumbra.render(box_scene, spp=4, seed=9, threads=1)
    b = penumbra.render(box_scene, spp=4, seed=9, threads=2)
    c = penumbra.render(box_scene, spp=4, seed=10, threads=2)
    assert torch.equal(a, b)
    assert not torch.equal(a, c)


def test_images_are_not_copied(box_scene):
    image = penumbra.render(box_scene, spp=1, seed=0)
    array = image.numpy()
    assert array.base is not None  # a view of the native image, not a copy
    assert np.shares_memory(array, image.numpy())


def test_sensors_by_index_and_id(box_scene):
    assert [s[0] for s in box_scene.sensors()] == ["front", "side"]
    side = penumbra.render(box_scene, spp=2, seed=0, sensor="side")
    assert tuple(side.shape) == (16, 16, 3)
    assert torch.equal(side, penumbra.render(box_scene, spp=2, seed=0, sensor=1))
    with pytest.raises(penumbra.Error, match="unknown sensor 'top'"):
        penumbra.render(box_scene, sensor="top")
    with pytest.raises(penumbra.Error, match="unknown sensor '5' \\(the scene's sensors: 0 \\(front\\), 1 \\(side\\)\\)"):
        penumbra.render(box_scene, sensor=5)


def test_errors_are_exceptions_with_penumbras_message(box_scene, tmp_path):
    with pytest.raises(penumbra.Error, match="missing.xml"):
        penumbra.load_file(tmp_path / "missing.xml")
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0">\n  <shape type="cube">\n    <bsdf type="nope"/>\n  </shape>\n</scene>\n')
    with pytest.raises(penumbra.Error, match="bad.xml:3"):
        penumbra.load_file(bad)
    with pytest.raises(penumbra.Error, match="unknown parameter 'white.reflectanse'.*did you mean"):
        penumbra.render(box_scene, params={"white.reflectanse": torch.zeros(3)})
    with pytest.raises(ValueError, match="expected shape \\(3,\\)"):
        penumbra.render(box_scene, params={"white.reflectance": torch.zeros(4)})
    with pytest.raises(TypeError, match="float32"):
        penumbra.render(box_scene, params={"white.reflectance": torch.zeros(3, dtype=torch.float64)})
    with pytest.raises(penumbra.Error, match="unknown method 'nope'"):
        penumbra.render(box_scene, method="nope")
    with pytest.raises(penumbra.Error, match="option 'q' is not an option of method psdr"):
        penumbra.render(box_scene, q=0.3)


def test_nan_parameter_renders_nothing(box_scene):
    reference = penumbra.render(box_scene, spp=2, seed=0)
    with pytest.raises(penumbra.Error, match="non-finite"):
        penumbra.render(box_scene, params={"white.reflectance": torch.tensor([0.5, float("nan"), 0.5])}, spp=2)
    # The scene kept its values.
    assert torch.equal(penumbra.render(box_scene, spp=2, seed=0), reference)


def test_methods_are_listed():
    m = penumbra.methods()
    assert list(m)[:3] == ["psdr", "interior", "paths"]
    assert "primary_spp" in m["psdr"]["options"] and "q" in m["paths"]["options"]


def test_image_files_round_trip(tmp_path):
    image = torch.rand(5, 7, 3)
    penumbra.write_image(tmp_path / "a.exr", image)
    assert torch.allclose(penumbra.read_image(tmp_path / "a.exr"), image)


def test_ctrl_c_interrupts_a_long_render(tmp_path):
    import signal
    import subprocess
    import sys
    import time
    script = tmp_path / "long.py"
    script.write_text(
        "import sys, time, penumbra\n"
        "scene = penumbra.load_file(sys.argv[1])\n"
        "print('ready', flush=True)\n"
        "start = time.time()\n"
        "try:\n"
        "    penumbra.render(scene, spp=100000)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted after %.1f s' % (time.time() - start), flush=True)\n"
        "    penumbra.render(scene, spp=1)\n"  # the module still works afterwards
        "    print('ok', flush=True)\n")
    p = subprocess.Popen([sys.executable, str(script), str(SOURCE / "scenes" / "cbox" / "cbox.xml")],
                         stdout=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=30)
    assert p.returncode == 0
    assert "interrupted after" in out and out.strip().endswith("ok"), out
