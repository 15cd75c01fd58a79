"""Every attribute class rebuilds from its parameters() and validates its input."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om
from omnirender import attributes


def _examples():
    return [
        om.Color(0.1, 0.2, 0.3, 0.4),
        om.Color((1, 0, 0)),
        om.Material(diffuse=(1, 0.4, 0.6), specular=(1, 1, 1), shininess=40, opacity=0.5),
        om.PBRMaterial(base_color=(0.9, 0.1, 0.1), metallic=1, roughness=0.2, emission=(0.1, 0, 0)),
        om.Texture("some/file.png", wrap="clamp", filter="nearest", mipmap=False),
        om.Texture(np.zeros((2, 3, 3), np.uint8)),
        om.Texture(np.zeros((2, 2, 3), np.uint8), uv_set=1, offset=(0.5, 0), scale=(2, 3), rotation=30),
        om.PBRMaterial(
            base_color_texture=om.Texture(np.zeros((2, 2, 4), np.uint8)),
            alpha_mode="mask",
            alpha_cutoff=0.3,
            normal_scale=0.5,
            double_sided=False,
            emissive_strength=2,
        ),  # fmt: skip
        om.BumpMap(om.Texture(np.zeros((2, 2), np.uint8)), scale=0.1),
        om.TextureLayer(om.Texture(np.zeros((2, 2, 3), np.uint8)), blend="multiply", opacity=0.5),
        om.MultiTexture([om.TextureLayer(om.Texture(np.zeros((2, 2, 3), np.uint8)), blend="add")]),
        om.DrawStyle(mode="wireframe", line_width=2, point_size=3, cull="back", shading="flat"),
        om.DirectionalLight(direction=(1, -1, 0), color=(1, 0.9, 0.8), intensity=2),
        om.PointLight(position=(1, 2, 3), linear=0.1, quadratic=0.01, diffuse=(0.5, 0.5, 0.5)),
        om.SpotLight(position=(0, 5, 0), direction=(0, -1, 0), cutoff=20, exponent=4, specular=(1, 1, 1)),
        om.AmbientLight(color=(0.2, 0.3, 0.4), intensity=0.5),
        om.RectLight(position=(0, 3, 0), direction=(0, -1, 0), width=2, height=0.5, up=(1, 0, 0), two_sided=True),
        om.DiscLight(position=(0, 3, 0), direction=(0, -1, 0), radius=0.4, casts_shadows=False, intensity=3),
        om.LookAt(eye=(1, 2, 3), center=(0, 0, 0), up=(0, 0, 1)),
        om.Reflection(normal=(0, 1, 0), point=(0, 2, 0)),
        om.DirectionOfFlight(velocity=(1, 0, 1), up=(0, 1, 0), position=(1, 2, 3)),
        om.Polar(radius=2, azimuth=30, elevation=10, orient=True),
        om.Billboard(),
        om.Billboard(axis=(0, 1, 0)),
        om.ClipPlane(normal=(0, 0, 2), offset=0.5),
        om.Fog(color=(1, 1, 1), start=2, end=20, mode="exp2", density=0.3),
        om.Background((0.1, 0.2, 0.3, 0.0)),
        om.Tessellation(5),
        om.Highlight((0, 1, 1)),
        om.PickId(42),
        om.PickId("door"),
        om.Collidable(False),
        om.Shadowing(cast=False, receive=True),
        om.Mirror(0.4, plane=((0, 0, 2), 0.5)),
    ]


def _equal(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def test_every_exported_class_has_an_example():
    covered = {type(x) for x in _examples()}
    for name in attributes.__all__:
        cls = getattr(attributes, name)
        if isinstance(cls, type) and issubclass(cls, om.Attribute) and cls is not om.attributes.LightSource:
            assert cls in covered, f"no round-trip example for {name}"


@pytest.mark.parametrize("attr", _examples(), ids=lambda a: type(a).__name__)
def test_rebuild_from_parameters(attr):
    params = attr.parameters()
    clone = type(attr)(**params)
    assert type(clone) is type(attr)
    assert set(clone.parameters()) == set(params)
    for key, value in params.items():
        assert _equal(clone.parameters()[key], value), key


@pytest.mark.parametrize("attr", _examples(), ids=lambda a: type(a).__name__)
def test_slots_and_docstring(attr):
    assert not hasattr(attr, "__dict__"), f"{type(attr).__name__} must declare __slots__ everywhere"
    assert type(attr).__doc__


def test_categories():
    assert om.PointLight().category is om.Light
    assert om.AmbientLight().category is om.Light
    assert om.LookAt().category is om.Transform
    assert om.Billboard().category is om.Transform
    assert om.Material().category is om.Material
    assert isinstance(om.ClipPlane(), om.PolyAttribute)
    assert isinstance(om.PickId(1), om.PolyAttribute)
    assert isinstance(om.Collidable(), om.MonoAttribute)


def test_assignment_validates_and_bumps_version():
    m = om.Material()
    v = m.version
    m.shininess = 10
    assert m.version > v and m.shininess == 10.0
    with pytest.raises(ValueError, match="Material: shininess"):
        m.shininess = -1
    assert m.shininess == 10.0


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: om.Color(1.5, 0, 0), r"Color: r must be <= 1"),
        (lambda: om.Color(float("nan"), 0, 0), r"Color: r must be finite"),
        (lambda: om.Color((1, 0)), r"Color: give 3 or 4"),
        (lambda: om.Material(diffuse=(1, 2, 0)), r"Material: diffuse values must be in \[0, 1\]"),
        (lambda: om.Material(diffuse=(1, 0)), r"Material: diffuse must be 3 \(RGB\) or 4"),
        (lambda: om.Material(ambient=(float("inf"), 0, 0)), r"Material: ambient must be finite"),
        (lambda: om.Material(shininess=-1), r"Material: shininess must be >= 0"),
        (lambda: om.Material(opacity=1.5), r"Material: opacity must be <= 1"),
        (lambda: om.PBRMaterial(opacity=-0.1), r"PBRMaterial: opacity must be >= 0"),
        (lambda: om.PBRMaterial(metallic=2), r"PBRMaterial: metallic"),
        (lambda: om.PBRMaterial(roughness="x"), r"PBRMaterial: roughness must be a number"),
        (lambda: om.Texture(""), r"Texture: image"),
        (lambda: om.Texture(np.zeros((4, 4, 2))), r"Texture: image must be an \(H, W\)"),
        (lambda: om.Texture(np.full((2, 2, 3), 2.0)), r"Texture: image values"),
        (lambda: om.Texture("a.png", wrap="loop"), r"Texture: wrap must be one of"),
        (lambda: om.Texture("a.png", filter="cubic"), r"Texture: filter must be one of"),
        (lambda: om.DrawStyle(mode="dots"), r"DrawStyle: mode must be one of"),
        (lambda: om.DrawStyle(shading="gouraud"), r"DrawStyle: shading must be one of"),
        (lambda: om.DrawStyle(cull="sideways"), r"DrawStyle: cull must be one of"),
        (lambda: om.DrawStyle(line_width=0), r"DrawStyle: line_width must be > 0"),
        (lambda: om.DirectionalLight(direction=(0, 0, 0)), r"DirectionalLight: direction must not be the zero"),
        (lambda: om.PointLight(color=(2, 0, 0)), r"PointLight: color values must be in \[0, 1\]"),
        (lambda: om.PointLight(intensity=-1), r"PointLight: intensity must be >= 0"),
        (lambda: om.PointLight(constant=0), r"PointLight: constant, linear and quadratic must not all be 0"),
        (lambda: om.PointLight(linear=-1), r"PointLight: linear must be >= 0"),
        (lambda: om.SpotLight(cutoff=0), r"SpotLight: cutoff must be > 0"),
        (lambda: om.SpotLight(cutoff=91), r"SpotLight: cutoff must be <= 90"),
        (lambda: om.SpotLight(exponent=-2), r"SpotLight: exponent must be >= 0"),
        (lambda: om.SpotLight(direction=(0, 0, 0)), r"SpotLight: direction must not be the zero"),
        (lambda: om.LookAt(eye=(0, 0, 0), center=(0, 0, 0)), r"LookAt: eye and center must differ"),
        (lambda: om.LookAt(eye=(0, 0, 0), center=(0, 1, 0), up=(0, 2, 0)), r"LookAt: up must not be parallel"),
        (lambda: om.Billboard(axis=(0, 0, 0)), r"Billboard: axis must not be the zero"),
        (lambda: om.Billboard(axis=(0, 0, 3)), r"Billboard: axis must not be parallel to \+z"),
        (lambda: om.ClipPlane(normal=(0, 0, 0)), r"ClipPlane: normal must not be the zero"),
        (lambda: om.ClipPlane(offset=float("nan")), r"ClipPlane: offset must be finite"),
        (lambda: om.Fog(mode="fast"), r"Fog: mode must be one of"),
        (lambda: om.Fog(start=5, end=5), r"Fog: end must be > start"),
        (lambda: om.Fog(density=-1), r"Fog: density must be >= 0"),
        (lambda: om.Background((0, 0)), r"Background: color must be 3"),
        (lambda: om.Tessellation(9), r"Tessellation: level must be <= 8"),
        (lambda: om.Tessellation(1.5), r"Tessellation: level must be an integer"),
        (lambda: om.Tessellation(-1), r"Tessellation: level must be >= 0"),
        (lambda: om.Highlight((1, 1, 1.1)), r"Highlight: color values"),
        (lambda: om.PickId(-3), r"PickId: id must be an integer >= 0"),
        (lambda: om.PickId(True), r"PickId: id must be"),
        (lambda: om.Collidable("yes"), r"Collidable: enabled must be True or False"),
    ],
)
def test_validation_errors(make, match):
    with pytest.raises(ValueError, match=match):
        make()
