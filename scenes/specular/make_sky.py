"""Writes sky.exr, the smooth environment map of glass_ball.xml: a 64 x 32 latitude-longitude image whose
colours vary slowly and strongly with the direction (no edges), so that the image seen through the glass ball
moves with it. Run from the repository root with the Python module built:
    PYTHONPATH=build/python python3 scenes/specular/make_sky.py
"""
import numpy as np
import penumbra
import torch

H, W = 32, 64
v = (np.arange(H) + 0.5) / H
u = (np.arange(W) + 0.5) / W
V, U = np.meshgrid(v, u, indexing="ij")
r = 0.1 + 1.4 * (0.5 + 0.5 * np.sin(2 * np.pi * U)) * (1 - 0.7 * V)
g = 0.1 + 1.0 * (0.5 + 0.5 * np.cos(2 * np.pi * U + 1.0)) * (0.3 + 0.7 * V)
b = 0.1 + 1.2 * (1 - V) ** 2
penumbra.write_image("scenes/specular/sky.exr", torch.from_numpy(np.stack([r, g, b], -1).astype(np.float32)))
