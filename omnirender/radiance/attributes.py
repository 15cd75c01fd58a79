"""Radiance-specific attributes: ``Material``, ``Options``, ``Sky`` and ``Raw``.

Other engines have no handler for these classes, so they are pushed or added
passively and ignored there (``Sky`` is a light, but not one the other engines
know how to draw); the Radiance painters read them.  Everything except ``Raw``
is validated when it is made, so a scene cannot smuggle text into the
description: material types come from Radiance's list, string arguments from a
safe alphabet, numbers must be finite.

- :class:`Material` (mono): any Radiance material, pattern or mixture primitive
  for the shapes that follow, instead of the one converted from ``Material`` /
  ``PBRMaterial`` / ``Color``: ``om.radiance.Material("glass", (0.9, 0.9, 0.9))``
  (the type, the real arguments, optionally the string arguments).
- :class:`Options` (mono): ``rpict``/``rtrace`` parameters (``ab``, ``ad``,
  ``as_``, ``aa``, ``ar``, ``lw`` ...); the last one met applies to the render.
- :class:`Sky` (a light): a uniform sky of known radiance over the hemisphere
  around ``up``; it lights through interreflection, so it needs ``Options(ab>=1)``.
- :class:`Raw` (poly): trusted Radiance text written verbatim where it is met.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..attributes._params import Param, Parameterised, _numbers, check_direction, check_number, check_rgb
from ..attributes.appearance import PBRMaterial
from ..attributes.conversion import EngineSpecific, based_on, display_rgb, shininess_of_roughness
from ..core import Light, MonoAttribute, PolyAttribute
from . import rad

__all__ = ["Material", "Options", "Sky", "Raw", "PRIMITIVE_TYPES", "REAL_COUNTS"]

#: Radiance's material, pattern, texture and mixture types (``om.radiance.Material`` accepts these).
PRIMITIVE_TYPES = frozenset(
    {
        # materials
        "light", "illum", "glow", "spotlight", "mirror", "prism1", "prism2", "mist", "plastic", "metal",
        "trans", "plastic2", "metal2", "trans2", "dielectric", "interface", "glass", "plasfunc", "metfunc",
        "transfunc", "BRTDfunc", "plasdata", "metdata", "transdata", "BSDF", "aBSDF", "antimatter",
        "ashik2", "WGMDfunc",
        # textures and patterns
        "texfunc", "texdata", "colorfunc", "brightfunc", "colordata", "brightdata", "colorpict",
        "colortext", "brighttext", "spectrum", "specfile", "specfunc", "specdata", "specpict",
        # mixtures
        "mixfunc", "mixdata", "mixpict", "mixtext",
    }
)  # fmt: skip
#: How many real arguments the common types take (others are not checked here; Radiance checks them).
REAL_COUNTS: dict[str, tuple[int, ...]] = {
    "plastic": (5,),
    "metal": (5,),
    "trans": (7,),
    "glass": (3, 4),
    "light": (3,),
    "illum": (3,),
    "glow": (4,),
    "spotlight": (7,),
    "mirror": (3,),
    "dielectric": (5,),
    "interface": (8,),
    "plastic2": (6,),
    "metal2": (6,),
    "trans2": (8,),
}


def _check_type(owner: str, name: str, value: Any) -> str:
    if value not in PRIMITIVE_TYPES:
        import difflib

        close = difflib.get_close_matches(str(value), sorted(PRIMITIVE_TYPES), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(f"{owner}: {name} {value!r} is not a Radiance material, pattern or mixture type{hint}")
    return value


def _check_reals(owner: str, name: str, value: Any) -> tuple[float, ...]:
    return tuple(float(v) for v in _numbers(owner, name, value))


def _check_strings(owner: str, name: str, value: Any) -> tuple[str, ...]:
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{owner}: {name} must be a sequence of strings such as ('pat', '.'), got {value!r}")
    try:
        items = tuple(value)
    except TypeError:
        raise ValueError(f"{owner}: {name} must be a sequence of strings, got {value!r}") from None
    return tuple(rad.token(s, owner, f"{name} item") for s in items)


class Material(EngineSpecific, Parameterised, MonoAttribute):
    """Any Radiance material (or pattern, texture, mixture) primitive for the shapes that follow.

    ``kind`` is the Radiance type name, ``reals`` its real arguments and
    ``strings`` its string arguments, exactly as in a ``.rad`` file::

        om.radiance.Material("metal", (0.8, 0.6, 0.2, 0.9, 0.05))
        om.radiance.Material("glass", (0.96, 0.96, 0.96))

    It replaces the material converted from ``Material``/``PBRMaterial``/``Color``
    (a ``Texture`` still modifies it).  Types with a fixed argument count
    (``plastic``, ``metal``, ``trans``, ``glass``, ``light``, ``glow`` ...) are
    checked here; Radiance checks the others and its error names the node.
    """

    __slots__ = ("_kind", "_reals", "_strings")
    kind = Param(_check_type, "Radiance primitive type")
    reals = Param(_check_reals, "real arguments")
    strings = Param(_check_strings, "string arguments")

    def __init__(self, kind: str, reals: Sequence[float] = (), strings: Sequence[str] = ()) -> None:
        super().__init__()
        self.kind = kind
        self.reals = reals
        self.strings = strings
        counts = REAL_COUNTS.get(self._kind)
        if counts is not None and len(self._reals) not in counts:
            raise ValueError(
                f"Material: a Radiance {self._kind!r} takes {' or '.join(map(str, counts))} real arguments, "
                f"got {len(self._reals)}: {self._reals}"
            )

    def generic(self, current: Any) -> list[Any] | None:
        """Other engines: ``plastic`` and ``trans`` as Phong materials, ``metal`` as a metallic one, ``glass``
        as a mostly transparent glossy one, ``light``/``glow`` as emission (clipped to 1); patterns,
        textures and mixtures are Radiance's only."""
        kind, r = self._kind, self._reals
        rgb = display_rgb(r[:3]) if len(r) >= 3 else None
        if rgb is None:
            return None
        if kind in ("plastic", "plastic2", "trans") and len(r) >= 5:
            spec, rough = float(r[3]), float(r[4])
            changes: dict[str, Any] = {
                "diffuse": rgb,
                "specular": display_rgb(min(max(spec, 0.0), 1.0)),  # Radiance's specularity is linear
                "shininess": shininess_of_roughness(rough) if rough > 0 else 200.0,
            }
            if kind == "trans" and len(r) >= 6:
                changes["opacity"] = min(max(1.0 - float(r[5]), 0.0), 1.0)
            return [based_on(current, **changes)]
        if kind in ("metal", "metal2") and len(r) >= 5:
            return [PBRMaterial(base_color=rgb, metallic=1.0, roughness=min(max(float(r[4]) ** 0.5, 0.0), 1.0))]
        if kind in ("glass", "dielectric"):
            return [based_on(current, diffuse=rgb, specular=(1.0, 1.0, 1.0), shininess=200.0, opacity=0.2)]
        if kind in ("light", "glow", "illum", "spotlight"):
            return [based_on(current, diffuse=(0.0, 0.0, 0.0), emission=rgb)]
        return None


_int_ge0 = check_number(0.0, integer=True)
_int_ge1 = check_number(1.0, integer=True)
_ge0 = check_number(0.0)
_unit = check_number(0.0, 1.0)


def _optional(check: Any) -> Any:
    def run(owner: str, name: str, value: Any) -> Any:
        return None if value is None else check(owner, name, value)

    return run


class Options(Parameterised, MonoAttribute):
    """``rpict`` / ``rtrace`` rendering parameters; None keeps omnirender's default (in brackets).

    ``ab`` ambient bounces [0: direct light plus the ambient value, like GL],
    ``ad`` ambient divisions, ``as_`` ambient super-samples, ``aa`` ambient
    accuracy (0 turns the ambient cache off), ``ar`` ambient resolution,
    ``lw`` limit weight, ``lr`` limit reflection, ``dt`` direct threshold [0:
    every light is shadow-tested], ``dc`` direct certainty [1], ``dj`` direct
    jitter (soft shadows), ``ss`` specular sampling, ``st`` specular threshold,
    ``ds`` direct (source) subdivision [0.2: an area light is split until each
    piece is smaller than 0.2 of its distance; smaller values smooth the penumbra
    of ``RectLight``/``DiscLight`` shadows].
    The last ``Options`` met in the scene applies to the whole render;
    ``render(..., options=...)`` overrides it.
    """

    __slots__ = ("_ab", "_ad", "_as_", "_aa", "_ar", "_lw", "_lr", "_dt", "_dc", "_dj", "_ss", "_st", "_ds")
    ab = Param(_optional(check_number(0.0, 100.0, integer=True)), "ambient bounces")
    ad = Param(_optional(_int_ge1), "ambient divisions")
    as_ = Param(_optional(_int_ge0), "ambient super-samples")
    aa = Param(_optional(_ge0), "ambient accuracy")
    ar = Param(_optional(_int_ge0), "ambient resolution")
    lw = Param(_optional(_unit), "limit weight")
    lr = Param(_optional(check_number(-1000.0, 1000.0, integer=True)), "limit reflection")
    dt = Param(_optional(_unit), "direct threshold")
    dc = Param(_optional(_unit), "direct certainty")
    dj = Param(_optional(_unit), "direct jitter")
    ss = Param(_optional(_ge0), "specular sampling")
    st = Param(_optional(_unit), "specular threshold")
    ds = Param(_optional(_ge0), "direct (source) subdivision")

    #: omnirender's values for parameters left at None (Radiance's own defaults otherwise).
    DEFAULTS: dict[str, float] = {"ab": 0, "dt": 0.0, "dc": 1.0, "dj": 0.0}

    def __init__(
        self,
        ab: int | None = None,
        ad: int | None = None,
        as_: int | None = None,
        aa: float | None = None,
        ar: int | None = None,
        lw: float | None = None,
        lr: int | None = None,
        dt: float | None = None,
        dc: float | None = None,
        dj: float | None = None,
        ss: float | None = None,
        st: float | None = None,
        ds: float | None = None,
    ) -> None:
        super().__init__()
        self.ab, self.ad, self.as_, self.aa, self.ar, self.lw = ab, ad, as_, aa, ar, lw
        self.lr, self.dt, self.dc, self.dj, self.ss, self.st = lr, dt, dc, dj, ss, st
        self.ds = ds

    def arguments(self) -> list[str]:
        """Command-line arguments (``-ab 2 -ad 512 ...``) with omnirender's defaults filled in."""
        out: list[str] = []
        for name, value in self.parameters().items():
            if value is None:
                value = self.DEFAULTS.get(name)
            if value is None:
                continue
            flag = "-" + name.rstrip("_")
            out += [flag, str(int(value)) if isinstance(value, int) else rad.number(value, "Options")]
        return out


class Sky(Parameterised, Light):
    """A uniform sky: radiance ``color * intensity`` (W/sr/m^2 per channel) from every direction above the horizon.

    ``up`` is the zenith in the sky's coordinates (+y by default).  An
    unobstructed horizontal surface receives the irradiance ``pi * radiance``
    (W/m^2), i.e. ``179 * pi * luminance`` lux.  Radiance treats the sky as a
    ``glow`` source that lights through interreflection: use
    ``om.radiance.Options(ab=1)`` or more.  Other engines ignore it.
    """

    __slots__ = ("_color", "_intensity", "_up")
    color = Param(check_rgb, "sky colour (RGB in [0, 1])")
    intensity = Param(_ge0, "radiance scale (W/sr/m^2 for a white sky)")
    up = Param(check_direction, "zenith direction")

    def __init__(
        self, color: Sequence[float] = (1.0, 1.0, 1.0), intensity: float = 1.0, up: Sequence[float] = (0.0, 1.0, 0.0)
    ) -> None:
        super().__init__()
        self.color = color
        self.intensity = intensity
        self.up = up

    @property
    def radiance(self) -> tuple[float, float, float]:
        """``color * intensity`` in W/sr/m^2."""
        c, k = self._color, self._intensity
        return (c[0] * k, c[1] * k, c[2] * k)


class Raw(PolyAttribute):
    """Trusted, hand-written Radiance text, written verbatim where the attribute is met.

    Never build it from untrusted input: a line starting with ``!`` in a
    Radiance description runs a shell command.  Scene files refuse it unless
    loaded with ``om.load(path, trusted=True)`` (``scene_file_trusted_only``).
    """

    __slots__ = ("text",)
    #: scene files load this type only with ``trusted=True`` (see omnirender.scene.files)
    scene_file_trusted_only = True

    def __init__(self, text: str) -> None:
        super().__init__()
        if not isinstance(text, str):
            raise TypeError(f"Raw: text must be a string, got {type(text).__name__}")
        self.text = text

    def parameters(self) -> dict[str, Any]:
        return {"text": self.text}
