"""The GL frame as a list of stages: the default order, and a stage of the application's joining it."""

from __future__ import annotations

import numpy as np
import pytest

import omnirender as om

pytestmark = pytest.mark.gl

_TINT = "vec4 effect(vec2 uv) { return vec4(0.0, 0.0, 1.0, 1.0); }"


@pytest.fixture
def engine():
    from omnirender.gl import GLEngine

    e = GLEngine(size=(64, 48), samples=0)
    yield e
    e.release()


def mirror_scene() -> om.Node:
    root = om.Node("scene", [om.Camera.look_at((0, 2, 5), (0, 0.5, 0), fov=40),
                             om.PointLight(position=(1, 4, 3))])  # fmt: skip
    root.add(om.Node("floor", [om.Material(diffuse=(0.3, 0.3, 0.3)), om.Mirror(0.8), om.Rectangle(size=(5, 5))]))
    root.add(om.Node("ball", [om.Material(diffuse=(0.1, 0.9, 0.1)), om.Sphere(center=(0, 0.8, 0), radius=0.5)]))
    return root


class Tint(om.gl.GLTechnique):
    """One full-screen pass that paints the frame blue over its left half."""

    def prepare_pass(self, engine):
        engine.set_pass(om.gl.Pass("user tint", fullscreen=om.gl.FullScreen(_TINT), viewport=(0, 0, 32, 48)))


class TintStage(om.gl.FrameStage):
    name = "tint"

    def __init__(self) -> None:
        self.frames = 0

    def draw(self, frame, root) -> int:
        self.frames += 1
        return frame.run(Tint(), root)


def names(engine) -> list[str]:
    return [p["name"] for p in engine.stats["passes"]]


def test_the_default_stages_in_frame_order(engine):
    assert engine.stages.names() == ["pipelines", "shadow maps", "technique", "mirrors", "stereo"]
    engine.render(mirror_scene())
    order = names(engine)
    first = {
        stage: min(i for i, n in enumerate(order) if n.startswith(stage))
        for stage in ("shadow", "opaque", "mirror[0].mark")
    }
    assert first["shadow"] < first["opaque"] < first["mirror[0].mark"]


def test_a_user_stage_runs_where_it_was_added(engine):
    stage = TintStage()
    engine.add_stage(stage, after="technique")
    assert engine.stages.names() == ["pipelines", "shadow maps", "technique", "tint", "mirrors", "stereo"]
    image = engine.render(mirror_scene()).array
    order = names(engine)
    tint = order.index("user tint")
    assert order.index("overlay") < tint < order.index("mirror[0].mark")  # after the technique, before mirrors
    assert stage.frames == 1
    assert engine.stats["passes"][tint]["draw_calls"] == 1
    # the left half is the stage's blue where the mirror stage did not draw over it, the right half is not
    left, right = image[:, :32], image[:, 32:]
    assert (left[..., 2] > 200).mean() > 0.5 and (right[..., 2] > 200).mean() < 0.2
    assert np.all(image[0, :32, :3] == (0, 0, 255))  # the sky above the floor: nothing after the stage draws there


def test_a_user_stage_before_the_technique_is_painted_over(engine):
    engine.add_stage(TintStage(), before="technique")
    image = engine.render(om.Node("scene", [om.Camera.look_at((0, 0, 5), (0, 0, 0)),
                                            om.Background((1, 1, 1)), om.Box()])).array  # fmt: skip
    order = names(engine)
    assert order.index("user tint") < order.index("opaque")
    assert tuple(image[2, 2, :3]) == (0, 0, 255)  # the background of the left half keeps the stage's blue
    assert tuple(image[24, 30, :3]) != (0, 0, 255)  # the box, drawn after, covers it
    assert tuple(image[2, 60, :3]) == (255, 255, 255)  # the right half: the frame's clear colour


def test_stages_are_validated_and_removable(engine):
    with pytest.raises(ValueError, match="no stage named 'nope'"):
        engine.add_stage(TintStage(), before="nope")
    with pytest.raises(TypeError, match="FrameStage"):
        engine.add_stage(object())
    stage = TintStage()
    engine.add_stage(stage)
    assert engine.stages.names()[-1] == "tint"
    assert engine.remove_stage("tint") is stage
    assert "tint" not in engine.stages.names()
