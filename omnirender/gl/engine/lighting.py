"""Light uniforms: the pre-evaluated lights as view-space arrays for the shaders.

OpenGL's model: directional lights (``w = 0``), point and spot lights with
attenuation ``1 / (C + L d + Q d^2)`` and a spot factor ``cos^exponent`` inside
the cut-off cone.  Ambient terms of all lights add up with OpenGL's global
ambient (0.2).  A scene without any light gets a headlight.  Rectangle and disc
lights (type ``a``) add their polygons (view space) and frames (world space, for
their soft shadows) in slots of their own (:mod:`.area_glsl`).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ...attributes.photometry import GLOBAL_AMBIENT, HEADLIGHT
from .area_glsl import MAX_AREA_LIGHTS, AreaUniforms, bind_ltc
from .shaders import MAX_LIGHTS

__all__ = ["LightUniforms", "GLOBAL_AMBIENT", "HEADLIGHT"]


class LightUniforms:
    """Packed light arrays for one light switch state."""

    __slots__ = (
        "count",
        "types",
        "order",
        "pos",
        "diffuse",
        "specular",
        "attenuation",
        "spot",
        "exponent",
        "ambient",
        "dropped",
        "dropped_area",
        "has_area",
        "_bytes",
    )

    def __init__(self, lights: list[tuple[Any, np.ndarray]], view: np.ndarray, headlight: bool) -> None:
        from ...attributes import AmbientLight, AreaLight, DirectionalLight, SpotLight

        pos = np.zeros((MAX_LIGHTS, 4), np.float32)
        diffuse = np.zeros((MAX_LIGHTS, 3), np.float32)
        specular = np.zeros((MAX_LIGHTS, 3), np.float32)
        att = np.zeros((MAX_LIGHTS, 3), np.float32)
        att[:, 0] = 1.0
        spot = np.zeros((MAX_LIGHTS, 4), np.float32)
        spot[:, 3] = -2.0
        exponent = np.zeros(MAX_LIGHTS, np.float32)
        ambient = np.full(3, GLOBAL_AMBIENT)
        rot = view[:3, :3]
        n = 0
        types = []
        order: list[Any] = []  # the light of each index
        #: lights beyond MAX_LIGHTS (their ambient terms still count); warned about where a program lights with them
        self.dropped = 0
        self.dropped_area = 0  # area lights beyond MAX_AREA_LIGHTS
        areas = AreaUniforms()
        for light, matrix in lights:
            amb = getattr(light, "ambient", None)
            if amb is not None:
                ambient += np.asarray(amb, dtype=np.float64)
            if isinstance(light, AmbientLight):
                continue
            if isinstance(light, AreaLight) and areas.full():
                self.dropped_area += 1
                continue
            if n == MAX_LIGHTS:
                self.dropped += 1
                continue
            diffuse[n] = getattr(light, "diffuse", (1.0, 1.0, 1.0))
            specular[n] = getattr(light, "specular", (1.0, 1.0, 1.0))
            if isinstance(light, AreaLight):
                areas.add(light, matrix, view)
                p = view @ np.append(light.world_position(matrix), 1.0)
                pos[n] = (p[0], p[1], p[2], 1.0)
                types.append("a")
            elif isinstance(light, DirectionalLight):
                d = rot @ -light.world_direction(matrix)
                pos[n, :3] = d / np.linalg.norm(d)
                types.append("d")
            elif hasattr(light, "world_position"):
                p = view @ np.append(light.world_position(matrix), 1.0)
                pos[n] = (p[0], p[1], p[2], 1.0)
                att[n] = (light.constant, light.linear, light.quadratic)
                types.append("p")
                if isinstance(light, SpotLight):
                    axis = rot @ light.world_direction(matrix)
                    spot[n, :3] = axis / np.linalg.norm(axis)
                    spot[n, 3] = light.cos_cutoff
                    exponent[n] = light.exponent
                    types[-1] = "s"
            else:
                continue
            order.append(light)
            n += 1
        if n == 0 and headlight:
            pos[0, :3] = HEADLIGHT
            diffuse[0] = (1.0, 1.0, 1.0)
            specular[0] = (1.0, 1.0, 1.0)
            types.append("d")
            n = 1
        self.count = n
        self.types = "".join(types)
        self.order = order
        self.pos, self.diffuse, self.specular, self.attenuation = pos, diffuse, specular, att
        self.spot, self.exponent = spot, exponent
        self.ambient = ambient.astype(np.float32)
        self._bytes = {
            "u_lpos": pos,
            "u_ldiff": diffuse,
            "u_lspec": specular,
            "u_latt": att,
            "u_lspot": spot,
            "u_lexp": exponent,
            "u_lpoly": areas.poly,
            "u_larea": areas.world,
        }
        self.has_area = areas.count > 0

    def apply(self, program: Any) -> None:
        """Write the arrays into ``program``'s uniforms (those it has); warn once when it lights with a subset."""
        if self.dropped and program.get("u_ldiff", None) is not None:
            warnings.warn(
                f"GLEngine: more than {MAX_LIGHTS} lights; the rest are ignored (GLEngine(pipeline='deferred') "
                "draws any number)",
                stacklevel=4,
            )
            self.dropped = 0
        for name, data in self._bytes.items():
            u = program.get(name, None)
            if u is not None:
                # the compiler trims arrays to the elements a variant uses
                u.write(data[: u.array_length].tobytes())
        if self.dropped_area and program.get("u_lpoly", None) is not None:
            warnings.warn(
                f"GLEngine: more than {MAX_AREA_LIGHTS} rectangle/disc lights; the rest are ignored "
                "(GLEngine(pipeline='deferred') draws any number)",
                stacklevel=4,
            )
            self.dropped_area = 0
        if self.has_area:
            bind_ltc(program)
        u = program.get("u_ambient", None)
        if u is not None:
            u.write(self.ambient.tobytes())
        u = program.get("u_nlights", None)
        if u is not None:
            u.value = self.count
