"""Post-processing effects: the steps of an ``om.gl.PostProcess`` chain, parameters only.

Each effect is a scene component holding validated parameters (scene files
save and load it) and says which image-space passes it needs
(:meth:`Effect.passes`: ``om.gl.Pass`` descriptions with
``om.gl.FullScreen`` programs from :mod:`.glsl`).  ``stage`` says what it
reads: ``"depth"`` effects read the scene's depth (and normals rebuilt from
it) and run before transparent surfaces are composited, so the depth they
read is the depth of the colours they change; ``"color"`` effects read
colour only and run after.  Colours are linear light, high dynamic range
until a :class:`ToneMap`; the chain encodes sRGB at its end.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...attributes._params import Param, Parameterised, check_choice, check_number
from ...attributes.environment import Fog
from ...attributes.photometry import linear_rgb
from ...core.component import RenderingComponent
from ..engine.passes import FullScreen, Pass, Target
from . import glsl

__all__ = [
    "Effect",
    "EffectFrame",
    "FXAA",
    "ToneMap",
    "Bloom",
    "SSAO",
    "DepthFog",
    "Vignette",
    "LightShafts",
    "DepthOfField",
    "ColorGrading",
    "CustomEffect",
    "STAGES",
]

#: The stages of a chain, in the order they run: before and after transparent surfaces are composited.
STAGES = ("depth", "color")
_DTYPE = "f2"  # linear half floats: HDR light up to the tone mapper


@dataclass(frozen=True)
class EffectFrame:
    """What an effect's passes need of the frame: where its image comes from and goes, names, the camera.

    ``source`` and ``depth`` are ``(target, attachment)`` inputs (the image so far, the scene's depth),
    ``output`` the target the effect's last pass writes, ``prefix`` the start of the names of its own
    targets, ``label`` how errors name it (the effect, its place in the chain and the chain's node path).
    """

    engine: Any
    source: tuple[str, str]
    depth: tuple[str, str]
    output: Target
    prefix: str
    label: str
    camera: dict[str, Any] = field(default_factory=dict)

    def target(self, suffix: str, scale: float = 1.0, size: tuple[int, int] | None = None, dtype: str = _DTYPE):
        """One of the effect's own targets: one colour attachment, no depth."""
        return Target(f"{self.prefix}.{suffix}", colors=("color",), depth=False, dtype=dtype, scale=scale, size=size)

    def fullscreen(self, fragment: str, inputs: Mapping | None = None, uniforms: Mapping | None = None,
                   source: tuple[str, str] | None = None, textures: Mapping | None = None) -> FullScreen:  # fmt: skip
        """A full-screen program: the prelude, the frame's image and depth, the camera and ``uniforms``."""
        return FullScreen(
            glsl.PRELUDE + fragment,
            inputs={"u_input": source or self.source, "u_depth": self.depth, **(inputs or {})},
            uniforms={**self.camera, **(uniforms or {})},
            textures=textures or {},
            label=self.label,
        )


class Effect(Parameterised, RenderingComponent):
    """Base of post-processing effects: validated parameters and the passes that apply them."""

    __slots__ = ()
    #: "depth": reads the scene's depth, runs before transparent compositing; "color": colour only, after it
    stage = "color"

    def passes(self, frame: EffectFrame) -> list[Pass]:
        """The passes applying the effect: they read ``frame.source`` and the last writes ``frame.output``."""
        raise NotImplementedError

    def _one(self, frame: EffectFrame, fragment: str, uniforms: Mapping | None = None, **kw: Any) -> list[Pass]:
        name = type(self).__name__
        return [Pass(name, target=frame.output, fullscreen=frame.fullscreen(fragment, uniforms=uniforms, **kw))]


class FXAA(Effect):
    """Fast approximate anti-aliasing: blends along edges where the luma contrast is high (put it last).

    ``threshold`` is the contrast relative to the brightest neighbour below which a pixel is left alone,
    ``threshold_min`` the absolute contrast below which dark pixels are, ``span`` the longest blend along
    an edge in pixels.
    """

    __slots__ = ("_threshold", "_threshold_min", "_span")
    threshold = Param(check_number(0.0, 1.0), "relative luma contrast below which nothing is done")
    threshold_min = Param(check_number(0.0, 1.0), "absolute luma contrast below which nothing is done")
    span = Param(check_number(1.0, 16.0), "longest blend along an edge, pixels")

    def __init__(self, threshold: float = 0.125, threshold_min: float = 0.0312, span: float = 8.0) -> None:
        super().__init__()
        self.threshold, self.threshold_min, self.span = threshold, threshold_min, span

    def passes(self, frame: EffectFrame) -> list[Pass]:
        return self._one(frame, glsl.FXAA, {"u_threshold": self.threshold, "u_threshold_min": self.threshold_min,
                                            "u_span": self.span})  # fmt: skip


class ToneMap(Effect):
    """HDR tone mapping: linear light times ``2**exposure`` mapped into [0, 1] by ``operator``.

    Operators: ``"reinhard"`` (x / (1 + x)), ``"aces"`` (Narkowicz's ACES filmic fit), ``"uncharted2"``
    (Hable's filmic curve with white point ``white``), ``"hejl"`` (Hejl and Burgess-Dawson).  With
    ``auto_exposure`` the image's average luminance (exp of the mean log luminance) is mapped to ``key``
    (0.18: middle grey) before ``exposure`` applies.
    """

    __slots__ = ("_operator", "_exposure", "_auto_exposure", "_key", "_white")
    operator = Param(check_choice(*glsl.TONE_OPERATORS), "tone curve")
    exposure = Param(check_number(-16.0, 16.0), "exposure in stops (the light is scaled by 2**exposure)")
    auto_exposure = Param(lambda owner, name, v: _flag(owner, name, v), "scale the average luminance to key")
    key = Param(check_number(0.0, 10.0, min_open=True), "luminance the average is mapped to (auto exposure)")
    white = Param(check_number(0.0, 1000.0, min_open=True), "white point of the uncharted2 curve")

    def __init__(self, operator: str = "aces", exposure: float = 0.0, auto_exposure: bool = False,
                 key: float = 0.18, white: float = 11.2) -> None:  # fmt: skip
        super().__init__()
        self.operator, self.exposure, self.auto_exposure = operator, exposure, auto_exposure
        self.key, self.white = key, white

    def passes(self, frame: EffectFrame) -> list[Pass]:
        uniforms = {"u_scale": 2.0**self.exposure, "u_white": self.white}
        out = []
        inputs = None
        if self.auto_exposure:
            average = frame.target("average", size=(1, 1), dtype="f4")
            out.append(Pass("ToneMap average", target=average, fullscreen=frame.fullscreen(glsl.LOG_LUMINANCE)))
            inputs = {"u_average": (average.name, "color")}
            uniforms["u_key"] = self.key
        tone = frame.fullscreen(glsl.tone_map(self.operator, self.auto_exposure), inputs=inputs, uniforms=uniforms)
        return [*out, Pass("ToneMap", target=frame.output, fullscreen=tone)]


class Bloom(Effect):
    """Light above ``threshold`` (linear, soft ``knee``) spread by a chain of ``levels`` half-size blurs and
    added back times ``intensity`` (put it before the tone mapper: it reads HDR light)."""

    __slots__ = ("_threshold", "_intensity", "_levels", "_knee")
    threshold = Param(check_number(0.0, 1e4), "linear light above which pixels bloom")
    intensity = Param(check_number(0.0, 100.0), "how much of the blurred light is added")
    levels = Param(check_number(1, 8, integer=True), "half-size blur levels (larger: wider glow)")
    knee = Param(check_number(0.0, 1e4), "softness of the threshold")

    def __init__(self, threshold: float = 1.0, intensity: float = 1.0, levels: int = 5, knee: float = 0.1) -> None:
        super().__init__()
        self.threshold, self.intensity, self.levels, self.knee = threshold, intensity, levels, knee

    def passes(self, frame: EffectFrame) -> list[Pass]:
        levels = [frame.target(f"down{k}", scale=0.5 ** (k + 1)) for k in range(self.levels)]
        bright = frame.fullscreen(glsl.BLOOM_BRIGHT, uniforms={"u_threshold": self.threshold, "u_knee": self.knee})
        out = [Pass("Bloom threshold", target=levels[0], fullscreen=bright)]
        for k in range(1, self.levels):
            down = frame.fullscreen(glsl.BLOOM_DOWN, inputs={"u_level": (levels[k - 1].name, "color")})
            out.append(Pass(f"Bloom down {k}", target=levels[k], fullscreen=down))
        smaller = levels[-1]
        for k in range(self.levels - 2, -1, -1):
            up_target = frame.target(f"up{k}", scale=0.5 ** (k + 1))
            up = frame.fullscreen(glsl.BLOOM_UP, inputs={"u_level": (levels[k].name, "color"),
                                                         "u_smaller": (smaller.name, "color")})  # fmt: skip
            out.append(Pass(f"Bloom up {k}", target=up_target, fullscreen=up))
            smaller = up_target
        uniforms = {"u_intensity": self.intensity, "u_levels": float(self.levels)}
        combine = frame.fullscreen(glsl.BLOOM_COMBINE, inputs={"u_bloom": (smaller.name, "color")}, uniforms=uniforms)
        out.append(Pass("Bloom", target=frame.output, fullscreen=combine))
        return out


class SSAO(Effect):
    """Screen-space ambient occlusion: ``samples`` points in the hemisphere of ``radius`` (world units) around
    each surface's normal; a point behind the depth seen there by more than ``bias`` occludes.  The occlusion
    is computed at ``scale`` of the frame's size, blurred back to full size over pixels of similar depth
    (``blur``) and darkens the image by ``intensity`` (0: none, 1: fully)."""

    __slots__ = ("_radius", "_bias", "_samples", "_intensity", "_blur", "_scale")
    stage = "depth"
    radius = Param(check_number(0.0, 1e6, min_open=True), "world-space radius of the sample hemisphere")
    bias = Param(check_number(0.0, 1e6), "depth difference (world units) below which nothing occludes")
    samples = Param(check_number(4, 64, integer=True), "hemisphere samples per pixel")
    intensity = Param(check_number(0.0, 1.0), "how much occlusion darkens (0 to 1)")
    blur = Param(lambda owner, name, v: _flag(owner, name, v), "blur the occlusion (removes the sample pattern)")
    scale = Param(check_number(0.25, 1.0), "size of the occlusion buffer relative to the frame")

    def __init__(self, radius: float = 0.5, bias: float = 0.025, samples: int = 16, intensity: float = 1.0,
                 blur: bool = True, scale: float = 0.5) -> None:  # fmt: skip
        super().__init__()
        self.radius, self.bias, self.samples, self.intensity, self.blur = radius, bias, samples, intensity, blur
        self.scale = scale

    def passes(self, frame: EffectFrame) -> list[Pass]:
        raw = frame.target("occlusion", scale=self.scale)
        ao = frame.fullscreen(glsl.ssao(self.samples), uniforms={"u_radius": self.radius, "u_bias": self.bias})
        out = [Pass("SSAO occlusion", target=raw, fullscreen=ao)]
        if self.blur:  # at full size: the blur also brings the occlusion back to the frame's pixels by depth
            blurred = frame.target("blurred")
            blur = frame.fullscreen(glsl.BLUR, inputs={"u_source": (raw.name, "color")})
            out.append(Pass("SSAO blur", target=blurred, fullscreen=blur))
            raw = blurred
        apply = frame.fullscreen(glsl.SSAO_APPLY, inputs={"u_occlusion": (raw.name, "color")},
                                 uniforms={"u_intensity": self.intensity})  # fmt: skip
        return [*out, Pass("SSAO", target=frame.output, fullscreen=apply)]


class DepthFog(Effect):
    """Fog from the depth buffer with exactly ``om.Fog``'s equations and parameters (see :meth:`factor`):
    surfaces at eye distance d keep ``factor(d)`` of their colour.  Unlike ``om.Fog`` it applies after
    lighting to the whole opaque image, before transparent surfaces are composited."""

    __slots__ = ("_fog",)
    stage = "depth"

    def __init__(self, color: Any = (0.5, 0.5, 0.5), start: float = 1.0, end: float = 100.0, mode: str = "linear",
                 density: float = 0.05) -> None:  # fmt: skip
        super().__init__()
        try:
            fog = Fog(color=color, start=start, end=end, mode=mode, density=density)
        except ValueError as exc:
            raise ValueError(f"DepthFog: {str(exc).removeprefix('Fog: ')}") from None
        object.__setattr__(self, "_fog", fog)

    def parameters(self) -> dict[str, Any]:
        return self._fog.parameters()

    def factor(self, distance: Any) -> Any:
        """The fraction of a surface's colour kept at eye distance ``distance`` (``om.Fog.factor``)."""
        return self._fog.factor(distance)

    def passes(self, frame: EffectFrame) -> list[Pass]:
        from ..engine.compiler import FOG_MODES

        fog = self._fog
        uniforms = {"u_fog": (fog.start, fog.end, fog.density, FOG_MODES[fog.mode]),
                    "u_fog_color": linear_rgb(fog.color)}  # fmt: skip
        return self._one(frame, glsl.FOG, uniforms)


class Vignette(Effect):
    """Darkens towards the corners: the corners lose ``amount`` of their light, nothing changes within
    ``start`` (a fraction of the distance from the centre to a corner)."""

    __slots__ = ("_amount", "_start")
    amount = Param(check_number(0.0, 1.0), "fraction of the light the corners lose")
    start = Param(check_number(0.0, 1.0, max_open=True), "distance (fraction of the corner's) where it begins")

    def __init__(self, amount: float = 0.3, start: float = 0.5) -> None:
        super().__init__()
        self.amount, self.start = amount, start

    def passes(self, frame: EffectFrame) -> list[Pass]:
        return self._one(frame, glsl.VIGNETTE, {"u_amount": self.amount, "u_start": self.start})


class LightShafts(Effect):
    """Volumetric light shafts ("god rays") from the scene's lights (at most 4, the first ones), occluded by
    depth: light streams from each light's image towards the viewer where nothing nearer hides it.
    ``size`` is the radius of a light's glow (a fraction of the image height), ``decay`` the fall-off per
    sample along a shaft, ``intensity`` how much light is added."""

    __slots__ = ("_intensity", "_decay", "_size", "_samples")
    stage = "depth"
    intensity = Param(check_number(0.0, 100.0), "how much shaft light is added")
    decay = Param(check_number(0.5, 1.0), "fall-off per sample along a shaft")
    size = Param(check_number(0.0, 2.0, min_open=True), "radius of a light's glow, fraction of the image height")
    samples = Param(check_number(8, 256, integer=True), "samples along each shaft")

    def __init__(self, intensity: float = 0.6, decay: float = 0.97, size: float = 0.25, samples: int = 64) -> None:
        super().__init__()
        self.intensity, self.decay, self.size, self.samples = intensity, decay, size, samples

    def passes(self, frame: EffectFrame) -> list[Pass]:
        engine = frame.engine
        view, proj = engine.frame_view, engine.frame_projection
        lights, colors = [], []
        for light, matrix in engine.scene_lights[:4]:
            direction = getattr(light, "direction", None)
            if hasattr(light, "position"):
                p = matrix @ np.array([*light.position, 1.0])
            elif direction is not None:  # a directional light: its image is the point at infinity it comes from
                p = matrix @ np.array([*(-np.asarray(direction, float)), 0.0])
            else:
                continue
            eye = view @ p
            c = proj @ eye
            # behind the eye (an orthographic projection's w is 1 there too), or a direction an orthographic
            # camera has no image of (w 0): no shafts
            if c[3] <= 1e-9 or eye[2] >= 0.0:
                lights.append((0.0, 0.0, 1.0, 0.0))
            else:
                ndc = c[:3] / c[3]
                lights.append((ndc[0] * 0.5 + 0.5, ndc[1] * 0.5 + 0.5, min(ndc[2] * 0.5 + 0.5, 1.0), 1.0))
            strength = float(getattr(light, "intensity", 1.0))
            colors.append((*(np.asarray(linear_rgb(light.color)) * strength), 1.0))
        if not lights:
            return []  # no light, no shafts: the effect passes its input through (the chain skips it)
        size = engine.target_size
        where = {"u_count": len(lights), "u_lights": np.ravel(lights)}
        mask, shafts = frame.target("mask", scale=0.5), frame.target("shafts", scale=0.5)
        shape = {"u_size": self.size, "u_aspect": (size[0] / size[1], 1.0)}
        blur = {"u_samples": int(self.samples), "u_decay": self.decay, "u_light_colors": np.ravel(colors)}
        return [
            Pass("LightShafts mask", target=mask, fullscreen=frame.fullscreen(glsl.SHAFT_MASK, uniforms={**where,
                                                                                                           **shape})),
            Pass("LightShafts blur", target=shafts, fullscreen=frame.fullscreen(
                glsl.SHAFT_BLUR, inputs={"u_mask": (mask.name, "color")}, uniforms={**where, **blur})),
            Pass("LightShafts", target=frame.output, fullscreen=frame.fullscreen(
                glsl.SHAFT_ADD, inputs={"u_shafts": (shafts.name, "color")}, uniforms={"u_intensity": self.intensity})),
        ]  # fmt: skip


class DepthOfField(Effect):
    """Depth of field: surfaces at eye distance ``focus`` are sharp; the blur's radius grows linearly with the
    distance from it, to ``max_radius`` pixels at ``range`` world units from the focus and beyond.  The blur is
    gathered at ``scale`` of the frame's size and mixed in where the circle of confusion exceeds a pixel."""

    __slots__ = ("_focus", "_range", "_max_radius", "_samples", "_scale")
    stage = "depth"
    focus = Param(check_number(0.0, 1e9, min_open=True), "eye distance in focus")
    range = Param(check_number(0.0, 1e9, min_open=True), "distance from the focus where the blur is largest")
    max_radius = Param(check_number(0.0, 64.0), "largest blur radius, pixels")
    samples = Param(check_number(4, 128, integer=True), "taps per pixel")
    scale = Param(check_number(0.25, 1.0), "size of the blurred image relative to the frame")

    def __init__(self, focus: float = 5.0, range: float = 5.0, max_radius: float = 6.0, samples: int = 32,
                 scale: float = 0.5) -> None:  # fmt: skip
        super().__init__()
        self.focus, self.range, self.max_radius, self.samples = focus, range, max_radius, samples
        self.scale = scale

    def passes(self, frame: EffectFrame) -> list[Pass]:
        coc, blurred = frame.target("coc"), frame.target("blurred", scale=self.scale)
        circles = {"u_focus": self.focus, "u_range": self.range, "u_max": self.max_radius}
        gather = frame.fullscreen(glsl.depth_of_field(self.samples), inputs={"u_coc": (coc.name, "color")})
        composite = frame.fullscreen(glsl.DOF_COMPOSITE, inputs={"u_coc": (coc.name, "color"),
                                                                 "u_blurred": (blurred.name, "color")})  # fmt: skip
        return [
            Pass("DepthOfField circles", target=coc, fullscreen=frame.fullscreen(glsl.CIRCLE_OF_CONFUSION,
                                                                                uniforms=circles)),
            Pass("DepthOfField blur", target=blurred, fullscreen=gather),
            Pass("DepthOfField", target=frame.output, fullscreen=composite),
        ]  # fmt: skip


class ColorGrading(Effect):
    """Colour grading with a 3D table: ``table[r, g, b]`` (shape (N, N, N, 3), N in 2..64, values in [0, 1])
    is the display (sRGB-encoded) colour that display colour (r, g, b) / (N - 1) becomes, interpolated
    trilinearly; ``amount`` mixes the graded colour with the original.  :meth:`identity` makes a neutral
    table to start from."""

    __slots__ = ("_table", "_amount", "_texture")
    amount = Param(check_number(0.0, 1.0), "mix of the graded colour (1: the table's)")

    def __init__(self, table: Any = None, amount: float = 1.0) -> None:
        super().__init__()
        lut = self.identity(16) if table is None else _table(table)
        object.__setattr__(self, "_table", lut)
        self.amount = amount
        object.__setattr__(self, "_texture", None)

    @property
    def table(self) -> np.ndarray:
        """The (N, N, N, 3) table (a read-only copy of the one given)."""
        return self._table

    def parameters(self) -> dict[str, Any]:
        return {"table": self._table, "amount": self.amount}

    @staticmethod
    def identity(size: int = 16) -> np.ndarray:
        """The neutral table of ``size`` entries per axis: every colour maps to itself."""
        axis = np.linspace(0.0, 1.0, int(size))
        r, g, b = np.meshgrid(axis, axis, axis, indexing="ij")
        return np.stack([r, g, b], axis=-1)

    def texture(self) -> Any:
        """The table as an ``om.Texture`` strip (x = r + N b, y = g), 8 bits per channel, filtered linearly."""
        if self._texture is None:
            from ...attributes.appearance import Texture

            n = self._table.shape[0]
            strip = np.transpose(self._table, (1, 2, 0, 3)).reshape(n, n * n, 3)  # [g, b * n + r]
            rgba = np.concatenate([strip, np.ones((n, n * n, 1))], axis=-1)
            image = np.round(rgba[::-1] * 255.0).astype(np.uint8)  # images are stored top row first
            object.__setattr__(self, "_texture", Texture(image, wrap="clamp", filter="linear", mipmap=False))
        return self._texture

    def passes(self, frame: EffectFrame) -> list[Pass]:
        uniforms = {"u_size": float(self._table.shape[0]), "u_amount": self.amount}
        return self._one(frame, glsl.COLOR_GRADING, uniforms, textures={"u_table": self.texture()})


class CustomEffect(Effect):
    """A user effect: a GLSL snippet defining ``vec4 effect(vec2 uv)`` and its uniforms.

    The snippet reads the image so far with ``texture(u_input, uv)`` (linear colour) and may use the
    prelude of every effect (:data:`.glsl.PRELUDE`: ``u_depth``, ``depth_at``, ``view_position``,
    ``view_normal``, ``view_ray``, ``luminance``, ``u_resolution``, ``to_srgb``/``to_linear``).
    ``reads_depth=True`` puts it in the depth stage (before transparent compositing); ``uniforms`` maps
    uniform names the snippet declares to numbers or sequences of numbers.
    """

    __slots__ = ("_name", "_glsl", "_uniforms", "_reads_depth")
    name = Param(lambda owner, name, v: _label(owner, v), "the effect's name (in errors and pass reports)")
    glsl = Param(lambda owner, name, v: _snippet(owner, v), "GLSL defining vec4 effect(vec2 uv)")
    uniforms = Param(lambda owner, name, v: _uniforms(owner, v), "uniform values by name")
    reads_depth = Param(lambda owner, name, v: _flag(owner, name, v), "runs before transparent compositing")

    def __init__(self, name: str, glsl: str, uniforms: Mapping[str, Any] | None = None,
                 reads_depth: bool = False) -> None:  # fmt: skip
        super().__init__()
        self.name, self.glsl, self.uniforms, self.reads_depth = name, glsl, uniforms or {}, reads_depth

    @property
    def stage(self) -> str:  # type: ignore[override]
        return "depth" if self.reads_depth else "color"

    def passes(self, frame: EffectFrame) -> list[Pass]:
        return [Pass(self.name, target=frame.output, fullscreen=frame.fullscreen(self.glsl, uniforms=self.uniforms))]


# -- checks ----------------------------------------------------------------------------------------------------
def _flag(owner: str, name: str, value: Any) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{owner}: {name} must be True or False, got {value!r:.60}")
    return bool(value)


def _label(owner: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip() or len(value) > 80:
        raise ValueError(f"{owner}: name must be a non-empty string of at most 80 characters, got {value!r:.60}")
    return value


def _snippet(owner: str, value: Any) -> str:
    if not isinstance(value, str) or "effect" not in value:
        raise ValueError(
            f"{owner}: glsl must be GLSL source text defining vec4 effect(vec2 uv) (read the image with "
            f"texture(u_input, uv)), got {value!r:.60}"
        )
    if len(value) > 100_000:
        raise ValueError(f"{owner}: glsl is {len(value)} characters long; keep a snippet under 100000")
    return value


def _uniforms(owner: str, value: Any) -> dict[str, Any]:
    from ..engine.passes import uniform_pairs

    if not isinstance(value, Mapping):
        raise ValueError(f"{owner}: uniforms must map uniform names to numbers, got {value!r:.60}")
    reserved = {"u_input", "u_depth", "u_proj", "u_inv_proj", "u_resolution"} & set(value)
    if reserved:
        raise ValueError(f"{owner}: uniforms {sorted(reserved)} are set by the chain; give your uniforms other names")
    uniform_pairs(value, owner)  # names are identifiers, values finite numbers
    return dict(value)


def _table(value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value)  # the shape is checked before a float copy: a huge table is refused, not copied
    except (TypeError, ValueError):
        arr = np.zeros(0)
    if (
        arr.ndim != 4
        or arr.shape[3] != 3
        or not arr.shape[0] == arr.shape[1] == arr.shape[2]
        or not (2 <= arr.shape[0] <= 64)
    ):
        raise ValueError(
            f"ColorGrading: table must have shape (N, N, N, 3) with N in 2..64 (table[r, g, b] = new colour), "
            f"got {arr.shape}; ColorGrading.identity(16) is a neutral one"
        )
    try:
        arr = np.array(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("ColorGrading: table must hold numbers (display colours in [0, 1])") from None
    if not np.all(np.isfinite(arr)) or arr.min() < 0.0 or arr.max() > 1.0:
        raise ValueError("ColorGrading: table values must be display colours in [0, 1]")
    arr.setflags(write=False)
    return arr
