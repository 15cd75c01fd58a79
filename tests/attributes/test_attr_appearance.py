"""Appearance attributes: colours, materials, textures, draw style."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om


def test_color_forms():
    assert om.Color(1, 0.5, 0).rgba == (1.0, 0.5, 0.0, 1.0)
    assert om.Color((0, 0, 1, 0.25)).rgba == (0.0, 0.0, 1.0, 0.25)
    assert om.Color(np.array([0.2, 0.2, 0.2])).rgb == (0.2, 0.2, 0.2)


def test_material_colours_are_rgb_and_transparency_hint():
    m = om.Material(diffuse=(1, 0, 0, 0.3))
    assert m.diffuse == (1.0, 0.0, 0.0)
    assert "transparent" not in m.hints
    assert "transparent" in om.Material(opacity=0.5).hints
    assert "transparent" in om.PBRMaterial(opacity=0.2).hints


def test_texture_from_array_gray_rgb_rgba_float():
    gray = np.array([[0, 255], [128, 64]], np.uint8)
    a = om.Texture(gray).image_array()
    assert a.shape == (2, 2, 4) and a.dtype == np.uint8
    assert a[0, 1].tolist() == [255, 255, 255, 255] and a[1, 0].tolist() == [128, 128, 128, 255]
    rgb = om.Texture(np.ones((3, 2, 3))).image_array()
    assert rgb.shape == (3, 2, 4) and np.all(rgb == 255)
    rgba = np.zeros((1, 1, 4), np.uint8)
    rgba[0, 0] = (1, 2, 3, 4)
    t = om.Texture(rgba)
    assert t.image_array()[0, 0].tolist() == [1, 2, 3, 4]
    assert t.image_array() is t.image_array()  # cached
    assert t.path is None
    assert not t.image_array().flags.writeable


def test_texture_path_is_lazy_and_loads_with_pillow(tmp_path):
    from PIL import Image

    path = tmp_path / "tex.png"
    t = om.Texture(path)  # no file yet: loading is lazy
    assert t.path == str(path)
    arr = np.zeros((4, 5, 3), np.uint8)
    arr[0, 0] = (255, 0, 0)
    Image.fromarray(arr).save(path)
    img = t.image_array()
    assert img.shape == (4, 5, 4) and img[0, 0].tolist() == [255, 0, 0, 255]
    t.image = np.zeros((2, 2, 4), np.uint8)  # replacing the image drops the cache
    assert t.image_array().shape == (2, 2, 4)


def test_texture_errors_name_the_path(tmp_path):
    missing = tmp_path / "nope.png"
    with pytest.raises(FileNotFoundError, match="nope.png"):
        om.Texture(missing).image_array()
    bad = tmp_path / "bad.png"
    bad.write_text("not an image")
    with pytest.raises(ValueError, match="bad.png"):
        om.Texture(bad).image_array()


def test_drawstyle_cull_booleans():
    assert om.DrawStyle(cull=True).cull == "back"
    assert om.DrawStyle(cull=False).cull == "none"
    assert om.DrawStyle(cull="front").cull == "front"


def test_texture_integer_lists_become_uint8():
    t = om.Texture([[[255, 0, 0], [0, 255, 0]]])
    assert t.image.dtype == np.uint8
    assert t.image_array()[0, 1].tolist() == [0, 255, 0, 255]
    with pytest.raises(ValueError, match=r"Texture: image integer values must be in \[0, 255\]"):
        om.Texture([[[256, 0, 0]]])


def test_resolved_appearances_are_the_dataclass_made_from_their_fields():
    """resolve_appearance builds its results without the frozen dataclass's __init__ (a hot path): they must be
    the same objects the dataclass makes from the same fields (equality, hash, repr, frozen, a fresh extras)."""
    import dataclasses

    from omnirender.attributes.surface import Appearance, resolve_appearance

    texture = om.Texture(np.zeros((2, 2, 3), np.uint8))
    stacks = [
        [],
        [om.Color(0.2, 0.4, 0.6, 0.5)],
        [om.Material(diffuse=(0.3, 0.4, 0.5), specular=(1, 1, 1), shininess=7, opacity=0.25)],
        [om.Material(), om.Color(0.9, 0.1, 0.1)],
        [om.PBRMaterial(base_color=(0.2, 0.3, 0.4), metallic=0.5, roughness=0.3, base_color_texture=texture)],
        [om.PBRMaterial(opacity=0.5, alpha_mode="mask", alpha_cutoff=0.3, double_sided=False)],
    ]
    for stack in stacks:
        got = resolve_appearance(stack, texture if not stack else None)
        made = Appearance(**{f.name: getattr(got, f.name) for f in dataclasses.fields(Appearance)})
        assert got == made and hash(got) == hash(made) and repr(got) == repr(made)
        assert set(vars(got)) == set(vars(made))
        with pytest.raises(dataclasses.FrozenInstanceError):
            got.alpha = 0.0  # type: ignore[misc]
        assert got.extras == {} and got.extras is not resolve_appearance(stack).extras
