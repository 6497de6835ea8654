"""The examples in examples/ run end to end (--quick) and recover what they claim to. Each quick run is
deterministic (fixed seeds); the bounds leave a margin of about 2x below the factors the quick runs reach
(recover_material: albedo error /7.7, alpha error /90; multiview_mesh: distance /4.1; neural_texture: texture
error /9, image loss /7), and a run that did not optimize (error unchanged or grown) fails."""
import re

from conftest import run_example


def summary(stdout):
    """{name: (before, after)} from the example's final 'summary:' line ('name a -> b')."""
    line = [l for l in stdout.splitlines() if l.startswith("summary:")][-1]
    return {m[0]: (float(m[1]), float(m[2])) for m in re.findall(r"(\w+) ([-+.\deE]+) -> ([-+.\deE]+)", line)}


def test_recover_material(tmp_path):
    s = summary(run_example("recover_material.py", "--quick", "--out", str(tmp_path)))
    albedo, alpha = s["albedo_error"], s["alpha_error"]
    assert albedo[1] < 0.15 and albedo[1] < albedo[0] / 3, albedo
    assert alpha[1] < alpha[0] / 20, alpha
    assert all((tmp_path / f).exists() for f in ["target.png", "initial.png", "final.png"])


def test_multiview_mesh(tmp_path):
    s = summary(run_example("multiview_mesh.py", "--quick", "--out", str(tmp_path)))
    distance = s["distance"]
    assert distance[1] < distance[0] / 2, distance
    assert (tmp_path / "final_front.png").exists() and (tmp_path / "final.obj").exists()


def test_neural_texture(tmp_path):
    s = summary(run_example("neural_texture.py", "--quick", "--out", str(tmp_path)))
    texture, loss = s["texture_error"], s["image_loss"]
    assert texture[1] < texture[0] / 4, texture
    assert loss[1] < loss[0] / 3, loss
    assert (tmp_path / "texture_final.png").exists()
