"""penumbra: a physics-based differentiable renderer, from Python and PyTorch.

    import penumbra, torch
    scene = penumbra.load_file("scene.xml", spp=64)          # keyword arguments override <default> values
    params = scene.params()                                   # name -> torch.Tensor (Mitsuba traverse() keys)
    albedo = params["white.reflectance"].clone().requires_grad_()
    image = penumbra.render(scene, params={"white.reflectance": albedo}, spp=16, seed=1)
    loss = ((image - target) ** 2).mean()
    loss.backward()                                           # penumbra's reverse mode, method "psdr" by default

See docs/python.md. Every derivative method of the command line (`penumbra derivative --method ...`) is
available as `method=` with its options as keyword arguments (`penumbra.methods()` lists them).
"""
from collections import OrderedDict
from collections.abc import MutableMapping

import numpy as np
import torch

from . import _penumbra
from ._penumbra import Error

__all__ = ["Error", "Scene", "SceneParameters", "load_file", "load_string", "render", "forward_derivative",
           "methods", "set_thread_count", "read_image", "write_image"]
__version__ = "0.11.0"

_threads = 0


def set_thread_count(n):
    """Worker threads of every later call (0: all cores). With several processes on one machine (one
    torch.distributed rank per process), give each rank cores // ranks so they do not oversubscribe."""
    global _threads
    if int(n) < 0:
        raise ValueError("set_thread_count: n must be >= 0")
    _threads = int(n)


def read_image(path):
    """An image file (.exr linear, .png/.jpg sRGB-decoded as stored) as an H x W x 3 float32 tensor."""
    return torch.from_numpy(_penumbra.read_image(str(path)))


def write_image(path, image):
    """Writes an H x W x 3 tensor or array: .exr (linear float) or .png (sRGB-encoded)."""
    if isinstance(image, torch.Tensor):
        image = image.detach().cpu().to(torch.float32).numpy()
    _penumbra.write_image(str(path), image)


def methods():
    """{method name: {"help": str, "options": {option: (type, help, choices)}}} — the derivative methods."""
    return OrderedDict((name, {"help": help_text, "options": OrderedDict((o[0], tuple(o[1:])) for o in options)})
                       for name, help_text, options in _penumbra.methods())


class Scene:
    """A loaded scene. Its parameters are read and written through params(); render() differentiates them."""

    def __init__(self, native):
        self._native = native
        self._entries = OrderedDict((e[0], (tuple(e[1]), e[2], e[3])) for e in native.entries())
        self._version = 0  # bumped whenever values are written into the scene
        self._written = {}  # entry index -> the values last written

    def sensors(self):
        """[(id, width, height)] of every sensor, in declaration order (render(sensor=) takes an index or id)."""
        return [tuple(s) for s in self._native.sensors()]

    def faces(self, shape):
        """The triangles of a shape's mesh as an F x 3 int64 tensor of vertex indices (Mitsuba's read-only
        `<shape>.faces`), in the order of `<shape>.vertex_positions` (a loader may renumber a file's vertices)."""
        return torch.from_numpy(self._native.faces(shape))

    def params(self):
        """The scene's parameters: an ordered mapping name -> float32 CPU tensor (a copy). Motions are values
        too: <shape>.translate (3), .rotate (3, a rotation vector in radians about the bounding-box center),
        .scale (1), <sensor>/<emitter>.translate/.rotate, all 0 for the scene as loaded."""
        return SceneParameters(self)

    def _index(self, name):
        return self._native.find(name)

    def _shape(self, name):
        return self._entries[self._canonical(name)][0]

    def _canonical(self, name):
        if name in self._entries:
            return name
        return self._native.entries()[self._native.find(name)][0]

    def _get(self, name):
        values = self._native.get(self._index(name))
        return torch.from_numpy(values.reshape(self._shape(name)))

    def _write(self, values):
        """Stages {name: tensor} and applies them (one BVH rebuild at most)."""
        checked = [(self._index(name), _as_values(name, value, self._shape(name))) for name, value in values.items()]
        # Values equal to those last written are skipped: a geometric change rebuilds the BVH, so rendering several
        # views of the same parameters must not pay for it once per view.
        changed = [(i, a) for i, a in checked if i not in self._written or not np.array_equal(self._written[i], a)]
        if not changed:
            return
        for index, array in changed:
            self._native.set(index, array)
        self._native.apply()
        for index, array in changed:
            self._written[index] = array.copy()
        self._version += 1

    def _sensor_index(self, sensor):
        if isinstance(sensor, str):
            ids = [s[0] for s in self.sensors()]
            if sensor not in ids:
                raise Error("unknown sensor '%s' (sensors: %s)" % (sensor, ", ".join(i or "<no id>" for i in ids)))
            return ids.index(sensor)
        return int(sensor)

    def __repr__(self):
        return "penumbra.Scene(%d parameters, sensors %s)" % (len(self._entries), [s[0] for s in self.sensors()])


class SceneParameters(MutableMapping):
    """name -> tensor, like Mitsuba's SceneParameters: assign new values, then update() writes them into the
    scene. render(scene, params=...) takes this mapping (or any dict of a subset) directly."""

    def __init__(self, scene):
        self._scene = scene
        self._values = OrderedDict((name, scene._get(name)) for name in scene._entries)
        self._modified = set()

    def __getitem__(self, name):
        return self._values[self._scene._canonical(name)]

    def __setitem__(self, name, value):
        name = self._scene._canonical(name)
        _as_values(name, value, self._scene._shape(name))  # checks dtype and shape now
        self._values[name] = value
        self._modified.add(name)

    def __delitem__(self, name):
        raise TypeError("scene parameters cannot be deleted")

    def __iter__(self):
        return iter(self._values)

    def __len__(self):
        return len(self._values)

    def update(self, values=None, **kwargs):
        """Writes the modified parameters (and those given here) into the scene."""
        if values:
            for k, v in dict(values).items():
                self[k] = v
        for k, v in kwargs.items():
            self[k] = v
        if self._modified:
            self._scene._write({k: self._values[k] for k in self._modified})
            self._modified.clear()

    def shape(self, name):
        return self._scene._shape(name)

    def __repr__(self):
        rows = ["  %-40s %s" % (k, tuple(v.shape)) for k, v in self._values.items()]
        return "SceneParameters(\n" + "\n".join(rows) + "\n)"


def _as_values(name, value, shape):
    """A float32 CPU numpy view of `value` with the parameter's shape; TypeError / ValueError otherwise."""
    if isinstance(value, torch.Tensor):
        if value.device.type != "cpu":
            raise TypeError("parameter '%s': tensors must be on the CPU (penumbra renders on the CPU), got %s"
                            % (name, value.device))
        if value.dtype != torch.float32:
            raise TypeError("parameter '%s': expected a float32 tensor, got %s" % (name, value.dtype))
        array = value.detach().contiguous().numpy()
    else:
        array = np.asarray(value, dtype=np.float32)
    if tuple(array.shape) != tuple(shape):
        if array.size == int(np.prod(shape)) and array.ndim == 1:
            array = array.reshape(shape)
        else:
            raise ValueError("parameter '%s': expected shape %s, got %s" % (name, tuple(shape), tuple(array.shape)))
    if not np.all(np.isfinite(array)):
        raise Error("parameter '%s': non-finite value (NaN or Inf); nothing was rendered" % name)
    return np.ascontiguousarray(array, dtype=np.float32).reshape(-1)


def _defines(defines):
    return {str(k): (("true" if v else "false") if isinstance(v, bool) else str(v)) for k, v in defines.items()}


def load_file(path, **defines):
    """Loads a Mitsuba 3 XML scene; keyword arguments override its <default> values (mitsuba -D)."""
    return Scene(_penumbra.load_file(str(path), _defines(defines)))


def load_string(xml, base_dir=".", **defines):
    """Loads a scene from an XML string; relative file names resolve against base_dir."""
    return Scene(_penumbra.load_string(xml, str(base_dir), _defines(defines)))


def _prepare(scene, params):
    """Writes the values of `params` (a mapping name -> tensor) into the scene; returns (names, tensors)."""
    if params is None:
        return [], []
    if not isinstance(params, (dict, MutableMapping)):
        raise TypeError("params must be a mapping name -> tensor (e.g. scene.params() or a dict)")
    names = [scene._canonical(k) for k in params.keys()]
    tensors = list(params.values())
    if isinstance(params, SceneParameters):
        params._modified.clear()
    scene._write(dict(zip(names, tensors)))
    return names, tensors


class _Render(torch.autograd.Function):
    """The image as a function of the parameter tensors; backward is the method's reverse mode."""

    @staticmethod
    def forward(ctx, scene, names, config, *tensors):
        ctx.scene, ctx.names, ctx.config = scene, names, config
        ctx.version = scene._version
        ctx.values = [t.detach().clone() for t in tensors]
        image = scene._native.render(config["spp"], config["seed"], config["threads"], config["sensor"],
                                     config["progress"])
        return torch.from_numpy(image)

    @staticmethod
    def backward(ctx, grad_image):
        scene, config = ctx.scene, ctx.config
        wanted = [i for i, need in enumerate(ctx.needs_input_grad[3:]) if need]
        grads = [None] * len(ctx.names)
        if wanted:
            if scene._version != ctx.version:  # the scene changed since forward: back to forward's values
                scene._write(dict(zip(ctx.names, ctx.values)))
            adjoint = grad_image.detach().to(torch.float32).contiguous().numpy()
            values = scene._native.gradient([scene._index(ctx.names[i]) for i in wanted], adjoint, config["spp"],
                                            config["seed_grad"], config["threads"], config["sensor"],
                                            config["method"], config["options"], config["progress"])
            for i, g in zip(wanted, values):
                grads[i] = torch.from_numpy(g).reshape(ctx.values[i].shape)
        return (None, None, None, *grads)


def _spp(spp, scene, sensor):
    """spp, or the sensor's <sampler> sample_count (Mitsuba's default)."""
    if spp is None:
        return scene._native.sample_count(sensor)
    if int(spp) <= 0:
        raise ValueError("spp must be positive, got %s" % spp)
    return int(spp)


def render(scene, params=None, spp=None, seed=0, seed_grad=None, method="psdr", sensor=0, threads=None,
           progress=False, **options):
    """Renders `scene` (sensor index or id) and returns an H x W x 3 float32 tensor.

    params: a mapping name -> tensor (scene.params() or a dict of some parameters); their values are written
    into the scene first, and the image is differentiable with respect to those that require grad: its
    backward runs penumbra's reverse mode with method `method` (psdr, interior, paths, ...; options as keyword
    arguments, e.g. primary_spp=8) and `spp` samples per pixel, seeded by seed_grad (default: derived from seed,
    so the gradient's samples are independent of the image's). progress=True draws a progress bar on stderr
    (when it is a terminal) for the render and its backward."""
    if not isinstance(scene, Scene):
        raise TypeError("render: expected a penumbra.Scene, got %s" % type(scene).__name__)
    _penumbra_method_check(method, options)
    names, tensors = _prepare(scene, params)
    sensor = scene._sensor_index(sensor)
    config = {"spp": _spp(spp, scene, sensor), "seed": int(seed), "threads": _threads if threads is None else int(threads),
              "sensor": sensor, "method": method, "options": dict(options), "progress": bool(progress),
              "seed_grad": int(seed) * 2 + 1 if seed_grad is None else int(seed_grad)}
    return _Render.apply(scene, names, config, *tensors)


def forward_derivative(scene, direction, params=None, spp=None, seed=0, method="psdr", sensor=0, threads=None,
                       batches=1, return_stderr=False, progress=False, **options):
    """Forward mode: the image derivative dI/dθ along `direction` (a mapping name -> tensor of each parameter's
    shape), at the values of `params` (if given). With batches > 1 and return_stderr, also the per-pixel
    standard error."""
    if not isinstance(scene, Scene):
        raise TypeError("forward_derivative: expected a penumbra.Scene, got %s" % type(scene).__name__)
    _penumbra_method_check(method, options)
    _prepare(scene, params)
    dirs = [(scene._index(k), _as_values(k, v, scene._shape(k)).tolist()) for k, v in direction.items()]
    sensor = scene._sensor_index(sensor)
    image, stderr = scene._native.derivative(dirs, _spp(spp, scene, sensor), int(seed),
                                             _threads if threads is None else int(threads), sensor, int(batches),
                                             method, dict(options), bool(progress))
    image = torch.from_numpy(image)
    if return_stderr:
        return image, (torch.from_numpy(stderr) if stderr is not None else None)
    return image


def _penumbra_method_check(method, options):
    known = methods()
    if method not in known:
        raise Error("unknown method '%s' (known methods: %s)" % (method, ", ".join(known)))
    for k in options:
        if k not in known[method]["options"]:
            owners = [m for m, info in known.items() if k in info["options"]]
            raise Error("option '%s' is not an option of method %s%s" % (
                k, method, " (it belongs to method %s)" % ", ".join(owners) if owners else ""))
