"""``om.render(engine="gl")`` options: the engine options the other engines take, and a helpful error otherwise."""

from __future__ import annotations

import pytest

import omnirender as om

pytestmark = pytest.mark.gl


class Unpaintable(om.Shape):
    __slots__ = ()


def scene_with(*items) -> om.Node:
    return om.Node("scene", [om.Camera.look_at(eye=(0, 0, 5)), om.Node("obj", list(items))])


def test_on_missing_is_passed_to_the_engine():
    scene = scene_with(Unpaintable(), om.Sphere())
    with pytest.raises(om.NoHandlerError, match="/scene/obj"):
        om.render(scene, engine="gl", size=(16, 16))
    image = om.render(scene, engine="gl", size=(16, 16), on_missing="skip")
    assert image.mask[8, 8]  # the sphere is still drawn
    with pytest.raises(ValueError, match="on_missing must be one of"):
        om.render(scene, engine="gl", size=(16, 16), on_missing="ignore")


def test_unknown_options_list_the_accepted_ones():
    with pytest.raises(TypeError, match=r"unknown options \['spp'\]; it takes size, mask, samples.*on_missing"):
        om.render(scene_with(om.Sphere()), engine="gl", size=(16, 16), spp=4)


@pytest.mark.parametrize("samples", [3, 6, -1, "4", 2.0, True])
def test_bad_sample_counts_are_refused_before_moderngl_sees_them(samples):
    # before: samples=3 failed inside moderngl ("the number of samples is invalid"), "4" with a bare TypeError
    with pytest.raises(ValueError, match=r"GLEngine: samples must be .*got"):
        om.render(scene_with(om.Sphere()), engine="gl", size=(8, 8), samples=samples)


@pytest.mark.parametrize("background", ["red", (1, 0), (1, 0, float("nan")), 5])
def test_bad_backgrounds_name_the_fix(background):
    # before: "red" raised a bare TypeError comparing str with float; (1, 0) was accepted silently
    with pytest.raises(ValueError, match=r"GLEngine: background must be .*om\.Background"):
        om.render(scene_with(om.Sphere()), engine="gl", size=(8, 8), background=background)


def test_a_background_argument_sets_the_clear_colour():
    image = om.render(scene_with(), engine="gl", size=(8, 8), background=(1, 0, 0))
    assert image.pixel(0, 0) == (255, 0, 0, 255)


def test_a_missing_texture_file_names_the_node(tmp_path):
    scene = scene_with(om.Texture(str(tmp_path / "missing.png")), om.Sphere())
    with pytest.raises(FileNotFoundError, match=r"missing\.png.*does not exist in node /scene/obj; fix the path"):
        om.render(scene, engine="gl", size=(8, 8))
    (tmp_path / "garbage.png").write_bytes(b"not a png")
    scene = scene_with(om.Texture(str(tmp_path / "garbage.png")), om.Sphere())
    with pytest.raises(ValueError, match=r"cannot read image file .*garbage\.png.* in node /scene/obj"):
        om.render(scene, engine="gl", size=(8, 8))


def test_points_without_a_draw_style_use_its_default_size():
    # before: GL drew them 4 px wide without a DrawStyle but 1 px with DrawStyle(), POV-Ray and Mitsuba 1 px
    import numpy as np

    points = om.PointSet(np.random.default_rng(0).uniform(-1, 1, (40, 3)))
    bare = om.render(scene_with(points), engine="gl", size=(64, 64), samples=0)
    styled = om.render(scene_with(om.DrawStyle(), points), engine="gl", size=(64, 64), samples=0)
    big = om.render(scene_with(om.DrawStyle(point_size=4), points), engine="gl", size=(64, 64), samples=0)
    assert 0 < bare.mask.sum() == styled.mask.sum() < big.mask.sum()


def test_a_released_gl_engine_says_so():
    from omnirender.gl import GLEngine

    scene = om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.Sphere()])
    engine = GLEngine(size=(8, 8))
    assert engine.render(scene).mask.any()
    engine.release()
    engine.release()  # a second release does nothing (it used to fail inside moderngl)
    with pytest.raises(RuntimeError, match="GLEngine: this engine was released.*create a new GLEngine"):
        engine.render(scene)


def test_a_texture_modulates_the_ambient_term():
    # before: ambient light ignored the texture (grey 139,139,139 where POV-Ray and Mitsuba show red 139,0,0)
    import numpy as np

    red = np.zeros((4, 4, 3), np.uint8)
    red[..., 0] = 255
    scene = om.Node(
        "s",
        [
            om.Camera.look_at(eye=(0, 0, 4)),
            om.AmbientLight(intensity=1),
            om.Material(diffuse=(1, 1, 1), ambient=(0.5, 0.5, 0.5)),
            om.Texture(red),
            om.Sphere(),
        ],
    )
    r, g, b, _ = om.render(scene, engine="gl", size=(32, 32)).pixel(16, 16)
    assert abs(r - 139) <= 2 and g == 0 and b == 0  # ambient 0.5 x intensity 1 x red, in sRGB: 139, as POV-Ray
