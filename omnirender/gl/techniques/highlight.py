"""The Phong-highlight technique of the VRS paper: highlights from a texture, in a second, additive pass.

``om.gl.PhongHighlight(texture, strength=1.0)`` put into a node draws the
subgraph after it in two passes: first as usual but without the Phong
specular term, then once more, added on top (``lequal`` depth, no depth
writes), with the colour of the highlight pattern ``texture`` looked up by
the reflected view direction (a sphere map in eye space: the texture's centre
is where the surface mirrors the viewer).  A texture of a soft spot gives
Phong's highlight, a star or a window-shaped pattern gives stylised ones.
:meth:`PhongHighlight.lobe` makes the Phong lobe ``cos^n`` as a texture.
Other engines ignore the technique and draw their own highlights.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..engine.attributes import Blend, DepthMask, DepthTest
from ..engine.passes import Pass, Shader
from ..engine.technique import GLTechnique

__all__ = ["PhongHighlight", "is_surface"]


def is_surface(item: Any) -> bool:
    """Pass predicate: filled surfaces (lines and points get no highlight)."""
    return item.state.kind == "mesh"


_LOOKUP = """uniform sampler2D u_highlight;
uniform float u_highlight_strength;
void pass_fragment(inout vec4 color, vec3 P, vec3 N) {
    float pp = dot(P, P);
    vec3 V = pp > 0.0 ? -P * inversesqrt(pp) : vec3(0.0, 0.0, 1.0);
    vec3 R = reflect(-V, N);                 // eye space: (0, 0, 1) mirrors the viewer
    float m = 2.0 * sqrt(R.x * R.x + R.y * R.y + (R.z + 1.0) * (R.z + 1.0));
    vec2 uv = m > 0.0 ? R.xy / m + 0.5 : vec2(0.5);
    color = vec4(texture(u_highlight, uv).rgb * u_highlight_strength, 1.0);
}"""


class PhongHighlight(GLTechnique):
    """Highlights of the subgraph after it from the pattern ``texture`` (an ``om.Texture``), added in a 2nd pass."""

    __slots__ = ("texture", "strength")

    def __init__(self, texture: Any, strength: float = 1.0) -> None:
        from ...attributes import Texture

        super().__init__(passes=2)
        if not isinstance(texture, Texture):
            raise ValueError(
                f"PhongHighlight: texture must be an om.Texture (e.g. om.Texture(PhongHighlight.lobe(40))), "
                f"got {type(texture).__name__}"
            )
        if isinstance(strength, bool) or not isinstance(strength, (int, float)) or not 0.0 <= strength <= 16.0:
            raise ValueError(f"PhongHighlight: strength must be a number in [0, 16], got {strength!r}")
        self.texture = texture
        self.strength = float(strength)

    @staticmethod
    def lobe(shininess: float = 40.0, size: int = 128) -> np.ndarray:
        """A sphere-map texture (RGBA uint8) of Phong's lobe ``cos(angle)^shininess`` around the mirror direction."""
        y, x = np.mgrid[0:size, 0:size]
        u = (x + 0.5) / size * 2.0 - 1.0
        v = (y + 0.5) / size * 2.0 - 1.0
        r2 = np.clip(u * u + v * v, 0.0, 1.0)
        z = 2.0 * (1.0 - r2) - 1.0  # the reflected direction's z for a sphere-map point (cos of its angle)
        lobe = np.clip(z, 0.0, 1.0) ** max(float(shininess), 1.0)
        encoded = np.where(lobe <= 0.0031308, lobe * 12.92, 1.055 * lobe ** (1 / 2.4) - 0.055)
        out = np.empty((size, size, 4), np.uint8)
        out[..., :3] = np.round(encoded * 255)[..., None]
        out[..., 3] = 255
        return out

    def prepare_pass(self, engine: Any) -> None:
        if engine.current_pass == 0:
            engine.set_pass(Pass("diffuse", shader=Shader(defines={"SPECULAR_OFF": True})))
        else:
            shader = Shader(unlit=True, fragment=_LOOKUP, textures={"u_highlight": self.texture},
                            uniforms={"u_highlight_strength": self.strength})  # fmt: skip
            engine.set_pass(Pass("highlight", items="opaque", select=is_surface, shader=shader, state=(
                Blend(True, "one", "one"), DepthMask(False), DepthTest(True, "lequal"))))  # fmt: skip
