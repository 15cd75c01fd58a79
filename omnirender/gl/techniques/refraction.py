"""Screen-space refraction: a surface shows the image of what lies behind it, displaced by its normal.

``om.gl.Refraction(texture, strength, tint)`` put into a node shades the
subgraph after it with ``texture`` (an ``om.gl.RenderTexture`` of the scene
seen by the frame's camera, usually leaving the refracting objects out with
the camera's group mask) read at the fragment's own screen position, moved by
``strength`` times the eye-space normal's x and y: guacamole's refraction
through a chained pipeline.  Given a render texture of the whole scene
instead, the refracting surface reads the previous frame of it (a pipeline
that sees its own output).  ``tint`` multiplies the light that passes and
``surface`` mixes in that much of the surface's own lit colour (highlights).
Other engines ignore the technique and draw the surface as it is.
"""

from __future__ import annotations

from typing import Any

from ..engine.passes import Pass, Shader
from ..engine.technique import GLTechnique

__all__ = ["Refraction"]

_SNIPPET = """
uniform sampler2D u_refracted;
uniform vec2 u_refraction_size;
uniform float u_refraction_strength;
uniform vec3 u_refraction_tint;
uniform float u_refraction_surface;
void pass_fragment(inout vec4 color, vec3 P, vec3 N) {
    vec2 uv = gl_FragCoord.xy / u_refraction_size + normalize(N).xy * u_refraction_strength;
    vec3 behind = texture(u_refracted, clamp(uv, 0.0, 1.0)).rgb;
    color = vec4(behind * u_refraction_tint + color.rgb * u_refraction_surface, 1.0);
}
"""


def _number(name: str, value: Any, low: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= 1.0:
        raise ValueError(f"Refraction: {name} must be a number in [{low:g}, 1], got {value!r}")
    return float(value)


class Refraction(GLTechnique):
    """Shade what follows with ``texture`` read in screen space, displaced by the normal (see the module docs)."""

    __slots__ = ("texture", "strength", "tint", "surface")

    def __init__(
        self,
        texture: Any,
        strength: float = 0.05,
        tint: tuple[float, float, float] = (1.0, 1.0, 1.0),
        surface: float = 0.2,
    ) -> None:
        from ...attributes import Texture

        if not isinstance(texture, Texture):
            raise ValueError(
                f"Refraction: texture must be an om.gl.RenderTexture (or om.Texture), got {type(texture).__name__}"
            )
        super().__init__()
        self.texture = texture
        self.strength = _number("strength", strength, -1.0)
        try:
            tint = tuple(float(c) for c in tint)
        except (TypeError, ValueError):
            tint = ()
        if len(tint) != 3 or not all(0.0 <= c <= 1.0 for c in tint):
            raise ValueError(f"Refraction: tint must be 3 numbers in [0, 1], got {tint!r}")
        self.tint = tint
        self.surface = _number("surface", surface, 0.0)

    def prepare_pass(self, engine: Any) -> None:
        uniforms = {
            "u_refraction_size": tuple(float(v) for v in engine.target_size),
            "u_refraction_strength": self.strength,
            "u_refraction_tint": self.tint,
            "u_refraction_surface": self.surface,
        }
        shader = Shader(fragment=_SNIPPET, textures={"u_refracted": self.texture}, uniforms=uniforms)
        engine.set_pass(Pass("refraction", shader=shader))
