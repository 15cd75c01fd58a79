"""Every engine-specific component round-trips through scene files by its qualified name."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import omnirender as om
from omnirender.core.component import RenderingComponent
from omnirender.scene.files import dumps, loads

SAMPLES = {
    "Finish": lambda m: m.Finish(phong=0.8, reflection=0.1),
    "Pigment": lambda m: m.Pigment(color=(1, 0, 0)),
    "Raw": lambda m: m.Raw("sphere { <0,0,0>, 1 }"),
    "BSDF": lambda m: m.BSDF({"type": "roughconductor", "alpha": 0.2}),
    "Emitter": lambda m: m.Emitter({"type": "constant", "radiance": {"type": "rgb", "value": 0.5}}),
    "Integrator": lambda m: m.Integrator({"type": "path", "max_depth": 4}),
    "Material": lambda m: m.Material("plasfunc", (0.5, 0.5, 0.5, 0.02, 0.05), strings=("refl", "my.cal")),
    "PhongHighlight": lambda m: m.PhongHighlight(om.Texture(m.PhongHighlight.lobe(20, size=8)), strength=0.5),
    "MaterialDescription": lambda m: m.MaterialDescription("unlit"),
    "CustomEffect": lambda m: m.CustomEffect("grey", "vec4 effect(vec2 uv) { return texture(u_input, uv); }", {"u": 2}),
    "PostProcess": lambda m: m.PostProcess([m.SSAO(radius=0.3), m.ToneMap("hejl", auto_exposure=True), m.FXAA()]),
    "Refraction": lambda m: m.Refraction(
        m.RenderTexture(om.Node("behind", [om.Sphere()]), om.Camera.look_at((0, 0, 5), mask="!glass"), (32, 16)),
        strength=0.1,
        tint=(0.9, 1.0, 0.95),
    ),
    "RenderTexture": lambda m: m.RenderTexture(
        om.Node("screen", [om.Color((1, 0, 0)), om.Sphere()]), om.Camera.look_at((0, 0, 5)), (32, 16), name="cam"
    ),
}
#: Raw differs by engine: each takes its own language
RAW = {"povray": "sphere { <0,0,0>, 1 }", "radiance": "void plastic red 0 0 5 1 0 0 0 0"}


def _components():
    for prefix in ("povray", "gl", "mitsuba", "radiance"):
        module = getattr(om, prefix)
        for name in module.__all__:
            cls = getattr(module, name)
            if inspect.isclass(cls) and issubclass(cls, RenderingComponent) and not name.startswith("SDL"):
                yield pytest.param(prefix, name, id=f"{prefix}.{name}")


def _same(a, b):
    if isinstance(a, om.Node):  # a render texture's scene: the same graph
        return (isinstance(b, om.Node) and a.name == b.name and len(a.items) == len(b.items)
                and all(_same(p, q) for p, q in zip(a.items, b.items, strict=True)))  # fmt: skip
    if isinstance(a, RenderingComponent):  # a component parameter (a technique's texture): equal parameters
        return type(a) is type(b) and _same(a.parameters(), b.parameters())
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and any(isinstance(x, RenderingComponent) for x in a):  # a chain's effects
        return isinstance(b, (list, tuple)) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, (list, tuple, np.ndarray)):
        return np.array_equal(np.asarray(a, dtype=object), np.asarray(b, dtype=object))
    return a == b


@pytest.mark.parametrize("fmt", ["json", "yaml"])
@pytest.mark.parametrize("prefix, name", list(_components()))
def test_engine_component_round_trips(prefix, name, fmt):
    module = getattr(om, prefix)
    make = SAMPLES.get(name)
    if name == "Raw":
        component = module.Raw(RAW[prefix])
    else:
        component = make(module) if make else getattr(module, name)()
    scene = om.Node("scene", [component, om.Sphere()])
    text = dumps(scene, fmt)
    assert f"{prefix}." in text
    again = loads(text, fmt, trusted=True).items[0]
    assert type(again) is type(component)
    assert _same(again.parameters(), component.parameters())
