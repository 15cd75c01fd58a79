"""Stencil shadow volumes: the VRS paper's exact hard shadows, as a GL technique.

``om.gl.ShadowVolumes()`` put into a node shades the subgraph after it
(the receivers) with exact hard shadows from every light with
``casts_shadows``, cast by the closed meshes of the whole scene that cast
shadows (``om.Shadowing``).  Passes, drawn into a float target with a stencil
buffer (light adds up linearly there), composited over the frame at the end:

1. ``ambient``: the receivers lit by the ambient light, emission and the
   lights that cast no shadows (this fills the depth buffer);
2. for each shadow-casting light: ``volume.back`` and ``volume.front``: the
   shadow volumes of the casters (a geometry shader fed triangles with their
   neighbours extrudes the silhouette edges to infinity and caps the volume
   with the light-facing triangles, depth clamped) counted into the stencil
   buffer with the depth-fail ("z-fail") rule, which is right also when the
   camera is inside a volume; then ``lit``: the receivers lit by that light
   alone, added where the count is 0;
3. ``resolve``: the sum, encoded for display, over the frame with its depth.

Limits: casters must be closed, consistently wound meshes (spheres, boxes,
tori, closed triangle sets; open surfaces are left out when
``geometry.closed`` is false, mirrored instances cast wrong volumes);
transparent receivers get the ambient pass only; ``LightSwitch`` inside the
scope is not honoured; the driver must offer depth-stencil textures.  Cost:
three passes and the volumes' fill per light.  Other engines ignore it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..engine.attributes import (
    Blend,
    ColorMask,
    CullFace,
    DepthClamp,
    DepthMask,
    DepthTest,
    PolygonOffset,
    StencilOp,
    StencilTest,
)
from ..engine.imagespace import resolve
from ..engine.passes import Clear, Pass, Shader, Target
from ..engine.shaders import MAX_LIGHTS
from ..engine.state import casts_shadows
from ..engine.technique import GLTechnique

__all__ = ["ShadowVolumes", "casts_volume"]

#: The float target the technique lights its scope in (its stencil counts the volumes).
TARGET = Target("shadow-volumes", dtype="f2", stencil=True)


def casts_volume(item: Any) -> bool:
    """Pass predicate: a closed opaque mesh that casts shadows (it has a well-defined volume)."""
    return casts_shadows(item) and bool(item.geometry.closed) and not item.transparent


class ShadowVolumes(GLTechnique):
    """Exact hard shadows by stencil shadow volumes for the subgraph after it (see the module docs)."""

    __slots__ = ()

    def __init__(self) -> None:
        super().__init__(passes=1)

    def supported(self, engine: Any) -> bool:
        raw = getattr(engine, "raw", None)
        return super().supported(engine) and raw is not None and raw.available

    def start(self, engine: Any) -> None:
        order = engine.light_order()
        casting = [i for i, light in enumerate(order) if getattr(light, "casts_shadows", False)]
        matrices = {id(light): m for light, m in engine.scene_lights}
        engine.technique_frame.data["lights"] = [(i, order[i], matrices.get(id(order[i]))) for i in casting]
        engine.technique_frame.data["size"] = len(order)

    def needs_pass(self, engine: Any) -> bool:
        return engine.current_pass < 2 + 3 * len(engine.technique_frame.data["lights"])

    def prepare_pass(self, engine: Any) -> None:
        data = engine.technique_frame.data
        lights = data["lights"]
        index = engine.current_pass
        if index == 0:
            on = np.ones(MAX_LIGHTS)
            on[[i for i, _, _ in lights]] = 0.0
            engine.set_pass(Pass("ambient", target=TARGET, clear=Clear(color=(0, 0, 0, 0), depth=1.0),
                                 shader=_select(on, ambient=1.0)))  # fmt: skip
            return
        if index == 1 + 3 * len(lights):
            engine.set_pass(Pass("resolve", fullscreen=resolve(TARGET.name)))
            return
        k, step = divmod(index - 1, 3)
        i, light, matrix = lights[k]
        if step < 2:
            engine.set_pass(
                Pass(
                    f"volume[{i}].{'back' if step == 0 else 'front'}",
                    items="opaque",
                    select=casts_volume,
                    scopes="items",
                    source="scene",
                    target=TARGET,
                    clear=Clear(color=None, depth=None, stencil=0) if step == 0 else None,
                    state=(
                        CullFace("front" if step == 0 else "back"),
                        StencilTest(True, "always", 0, 0xFF),
                        StencilOp("keep", "incr_wrap" if step == 0 else "decr_wrap", "keep", 0xFF),
                        ColorMask(False, False, False, False),
                        DepthMask(False),
                        DepthTest(True, "less"),
                        DepthClamp(True),
                        # volumes a little behind the surfaces they start on: a lit caster's own near cap
                        # then always fails the depth test with its far cap, and they cancel
                        PolygonOffset(0.0, 8.0),
                    ),
                    shader=Shader(
                        depth_only=True,
                        defines={"SHADOW_VOLUME": True},
                        uniforms={"u_volume_light": _light_vector(light, matrix)},
                    ),
                )  # fmt: skip
            )
            return
        on = np.zeros(MAX_LIGHTS)
        on[i] = 1.0
        engine.set_pass(
            Pass(
                f"lit[{i}]",
                items="opaque",
                target=TARGET,
                state=(
                    ColorMask(True, True, True, False),  # light adds up; coverage stays the ambient pass's
                    StencilTest(True, "equal", 0, 0xFF),
                    StencilOp(write_mask=0),
                    Blend(True, "one", "one"),
                    DepthMask(False),
                    DepthTest(True, "lequal"),
                ),
                shader=_select(on, ambient=0.0),
            )
        )


def _select(on: np.ndarray, ambient: float) -> Shader:
    return Shader(
        defines={"LIGHT_SELECT": True, "SHADOWS_OFF": True},
        uniforms={"u_light_on": tuple(float(v) for v in on), "u_ambient_on": ambient},
    )


def _light_vector(light: Any, matrix: np.ndarray) -> tuple[float, float, float, float]:
    """The light in world space: (position, 1) or (direction towards the light, 0)."""
    from ...attributes import DirectionalLight

    if isinstance(light, DirectionalLight):
        d = -light.world_direction(matrix)
        return (float(d[0]), float(d[1]), float(d[2]), 0.0)
    p = light.world_position(matrix)
    return (float(p[0]), float(p[1]), float(p[2]), 1.0)
