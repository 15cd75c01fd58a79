"""``Light.enabled`` (ArtiSynth's ``Light.setEnabled``): a disabled light is off in every engine, as if absent."""

from __future__ import annotations

import numpy as np
import pytest
from engines import marks, require

import omnirender as om

ENGINES = ("gl", "povray", "mitsuba", "radiance")


def scene(red_enabled: bool | None) -> om.Node:
    """The ball under a blue light and a red one (enabled, disabled, or None: absent)."""
    s = om.Node("s", [om.Camera.look_at((0, 0, 6), (0, 0, 0)), om.Background((0, 0, 0))])
    s.add(om.DirectionalLight(direction=(0, 0, -1), color=(0.2, 0.2, 1.0)))
    if red_enabled is not None:
        s.add(om.PointLight(position=(0, 0, 4), color=(1, 0, 0), intensity=1.0, enabled=red_enabled))
    s.add(om.Node("ball", [om.Material(diffuse=(1, 1, 1)), om.Sphere(radius=1)]))
    return s


def test_enabled_is_a_parameter_and_disabled_lights_leave_the_engines_light_list():
    light = om.PointLight(enabled=False)
    assert light.parameters()["enabled"] is False and om.AmbientLight(enabled=False).parameters()["enabled"] is False
    with pytest.raises(ValueError, match="enabled"):
        om.SpotLight(enabled="yes")
    seen = []

    class Probe(om.Engine):
        service = "probe"

        def eval(self, shape):
            seen.append(len(self.lights()))

    s = om.Node("s", [om.PointLight(), light, om.Node("n", [om.DirectionalLight(enabled=False), om.Sphere()])])
    Probe(on_missing="skip").run(s)
    assert seen == [1]
    light.enabled = True
    seen.clear()
    Probe(on_missing="skip").run(s)
    assert seen == [2]


@pytest.mark.parametrize("name", [pytest.param(n, marks=marks(n)) for n in ENGINES])
def test_a_disabled_light_adds_nothing_in_every_engine(name):
    require(name)
    on = om.render(scene(True), engine=name, size=(48, 36)).array[..., :3].astype(np.float64)
    off = om.render(scene(False), engine=name, size=(48, 36)).array[..., :3].astype(np.float64)
    absent = om.render(scene(None), engine=name, size=(48, 36)).array[..., :3].astype(np.float64)
    centre = (slice(14, 22), slice(20, 28))
    assert on[centre][..., 0].mean() > off[centre][..., 0].mean() + 40  # the red light shone when enabled
    assert off[centre][..., 2].mean() > 60  # the blue light still shines
    assert np.abs(off - absent).mean() < 1.0  # disabled = absent
