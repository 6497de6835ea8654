"""Differentiable photon mapping from PyTorch (method dpm-c, docs/dpm.md): backward is its reverse mode, equal to
its forward mode on the same samples, through a geometric motion (the caustic moves) and a light's intensity; the
scene's sppm settings it cannot follow are UserWarnings."""
import pytest
import torch

import penumbra
from conftest import SOURCE


def test_dpm_c_reverse_mode_equals_forward_mode():
    scene = penumbra.load_file(str(SOURCE / "scenes" / "dpm" / "reflector.xml"), res=16, photons=3000)
    g = torch.Generator().manual_seed(0)
    a = torch.rand(16, 16, 3, generator=g) - 0.3
    intensity = scene.params()["light.intensity"].clone().requires_grad_()
    image = penumbra.render(scene, params={"light.intensity": intensity}, spp=2, seed_grad=4, method="dpm-c",
                            paths=4)
    assert image.shape == (16, 16, 3) and float(image.sum()) > 0
    image.backward(a)
    v = torch.tensor([0.3, -0.2, 0.5])
    jv = penumbra.forward_derivative(scene, {"light.intensity": v}, spp=2, seed=4, method="dpm-c", paths=4)
    forward, reverse = float((a * jv).sum()), float((intensity.grad * v).sum())
    assert abs(forward) > 0
    assert abs(forward - reverse) < 1e-4 * float((a * jv).abs().sum())


def test_dpm_warns_about_a_constant_kernel():
    path = SOURCE / "scenes" / "dpm" / "reflector.xml"
    xml = path.read_text().replace('value="smooth"', 'value="constant"')
    scene = penumbra.load_string(xml, path.parent, res=8, photons=500)
    v = torch.tensor([1.0, 0.0, 0.0])
    with pytest.warns(UserWarning, match="constant kernel"):
        penumbra.forward_derivative(scene, {"light.intensity": v}, spp=1, method="dpm-c", paths=1)
    with pytest.warns(UserWarning, match="constant kernel"):
        image = penumbra.render(scene, params={"light.intensity": scene.params()["light.intensity"].clone()
                                               .requires_grad_()}, spp=1, method="dpm-c", paths=1)
        image.sum().backward()
