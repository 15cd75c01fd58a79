"""Pass descriptions: what one pass of a GL frame draws, where, and how (data, compared each frame).

A technique's ``prepare_pass`` describes its pass with ``engine.set_pass(Pass(...))``:

* **what**: ``items`` (``"all"``, ``"opaque"``, ``"transparent"``, ``"overlay"``,
  ``"none"`` or a set of them), a group ``mask`` on the nodes the items come
  from, ``select`` (a predicate on draw items, e.g. shadow casters), whether
  nested technique ``scopes`` are drawn;
* **where**: ``target`` (an offscreen :class:`Target` with named colour
  attachments and a depth texture that later passes can sample; None: the
  enclosing target), ``viewport`` (a pixel rectangle of the target: tiles of
  a shadow-map atlas), ``clear`` (:class:`Clear`);
* **how**: ``state`` (GL state attributes forced on every item, e.g.
  ``CullFace("front")``), ``fallback`` (applied where an item has the
  default), ``camera`` (an ``om.Camera`` or ``(view, projection)`` matrices,
  e.g. a light's), ``front_face`` (``"cw"`` for mirrored views), ``shader`` (:class:`Shader`: depth only, flat colour,
  unlit, user GLSL snippets), or ``fullscreen`` (:class:`FullScreen`: an
  image-space pass that draws one full-screen triangle instead of items), or
  ``custom`` (Python drawing code: ``custom(engine, draw)`` is called instead
  of drawing items; ``draw()`` draws what the pass selects, ``draw(Pass(...))``
  runs a nested pass, so the code can switch targets, cameras and full-screen
  effects while it draws, e.g. a compositing tree of renderers), and
  ``technique`` (which technique's passes draw the selected items: the
  engine's, or the frame's pipeline, e.g. the deferred one; a post-processing
  chain draws the scene with the pipeline into a float target).

Passes nest: the pass a nested technique describes is composed with the
enclosing one (:class:`Composed`): item classes intersect, masks and
predicates all apply, state/camera/shader settings of the inner pass win.
Descriptions are plain values; the engine compares them frame by frame and
rebuilds GPU objects (targets, programs) only when the description that needs
them changed.  ``Pass.scissored(box)`` derives the same pass limited to a pixel
rectangle (scissor and clear) without checking the description again: what a
technique that redraws a changed rectangle every frame uses (shadow maps'
partial updates).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...attributes._params import check_rgba
from .attributes import DEPTH_FUNCS  # depth comparisons by name -> moderngl's depth_func strings
from .glenum import GL_R11F_G11F_B10F

__all__ = [
    "Pass",
    "Target",
    "Clear",
    "Shader",
    "FullScreen",
    "Composed",
    "ITEM_CLASSES",
    "FRAME",
    "DEPTH_FUNCS",
    "FORMATS",
    "TECHNIQUES",
]

#: The classes of draw items: drawn in this order when a pass selects several.
ITEM_CLASSES = ("opaque", "transparent", "overlay")
_ALL = frozenset(ITEM_CLASSES)
_DTYPES = ("f1", "f2", "f4")
#: Texel formats of colour attachments (``Target.formats``): components, moderngl dtype, GL internal format
#: (None: moderngl's default for the dtype) and bytes per texel.  ``f1``/``f2``/``f4`` are RGBA of 8-bit
#: display values, 16-bit and 32-bit floats; ``rg32ui`` two unsigned integers (packed data, e.g. a G-buffer's
#: normal and material id); ``rg32f`` two floats; ``r11g11b10f`` three unsigned small floats in 32 bits
#: (additive light).
FORMATS = {
    "f1": (4, "f1", None, 4),
    "f2": (4, "f2", None, 8),
    "f4": (4, "f4", None, 16),
    "rg32ui": (2, "u4", None, 8),
    "rg32f": (2, "f4", None, 8),
    "r11g11b10f": (3, "f2", GL_R11F_G11F_B10F, 4),
}
#: What draws a pass's items (``Pass.technique``): None the pass itself at the frame's level and the engine's
#: technique below it; ``"engine"`` the engine's technique (``om.gl.Forward``: opaque, transparent, overlay);
#: ``"pipeline"`` the frame's pipeline (``om.gl.Deferred`` with ``GLEngine(pipeline="deferred")``);
#: ``"frame"`` what a frame runs over the whole scene (the pipeline, inside the scene's frame-level
#: post-processing chain when it has one), as a frame of the pass's target: targets sized relative to the
#: frame are sized to it (a stereo eye drawn whole into an eye-sized target).
TECHNIQUES = (None, "engine", "pipeline", "frame")


def _classes(items: Any) -> frozenset[str]:
    if isinstance(items, str):
        if items == "all":
            return _ALL
        if items == "none":
            return frozenset()
        items = (items,)
    try:
        chosen = frozenset(items)
    except TypeError:
        chosen = None
    if chosen is None or not chosen <= _ALL:
        raise ValueError(f"Pass: items must be 'all', 'none', one of {ITEM_CLASSES} or a set of them, got {items!r}")
    return chosen


def uniform_pairs(
    values: Mapping[str, Any] | Iterable[tuple[str, Any]] | None, owner: str
) -> tuple[tuple[str, Any], ...]:
    """Uniform values as a sorted tuple of (name, hashable value) pairs."""
    if values is None:
        return ()
    items = values.items() if isinstance(values, Mapping) else values
    out = []
    for name, value in items:
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"{owner}: uniform names must be GLSL identifiers, got {name!r}")
        if isinstance(value, (list, tuple, np.ndarray)):
            arr = np.asarray(value, dtype=np.float64).ravel()
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{owner}: uniform {name} has non-finite values {value!r}")
            value = tuple(float(v) for v in arr)
        elif isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{owner}: uniform {name} must be a number or a sequence of numbers, got {value!r}")
        elif not np.isfinite(value):
            raise ValueError(f"{owner}: uniform {name} is not finite ({value!r})")
        out.append((name, value))
    return tuple(sorted(out))


@dataclass(frozen=True)
class Target:
    """An offscreen render target, identified by ``name`` within a frame.

    ``colors`` names its colour attachments (fragment outputs 0, 1, ... in
    that order), ``depth`` adds a depth texture, ``dtype`` is ``"f1"`` (8 bits
    per channel, sRGB-encoded values like the screen), ``"f2"`` or ``"f4"``
    (linear floats), ``scale`` its size relative to the frame, or with
    ``relative="enclosing"`` relative to the framebuffer the pass is nested in
    (an offscreen pass inside another offscreen pass, e.g. inside a shadow map,
    gets that target's size); ``size = (width, height)`` fixes it in pixels
    instead (a square shadow map).  ``stencil`` gives the depth texture a
    stencil buffer (stencil techniques offscreen).  ``formats`` gives each
    colour attachment its own texel format (a key of :data:`FORMATS`; None:
    ``dtype`` for all), ``samples`` makes multisampled textures (0: one
    sample; shaders read them with ``sampler2DMS`` and ``texelFetch``).
    ``depth`` may also name another target of the frame whose depth texture
    this one shares (drawn first): a pass then tests against depth that an
    earlier pass wrote, without sampling what it tests against.
    Later passes sample it through :class:`FullScreen` ``inputs``,
    :class:`Shader` ``inputs`` or ``engine.target(name)``.
    """

    name: str
    colors: tuple[str, ...] = ("color",)
    depth: bool | str = True
    dtype: str = "f1"
    scale: float = 1.0
    relative: str = "frame"
    size: tuple[int, int] | None = None
    stencil: bool = False
    formats: tuple[str, ...] | None = None
    samples: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Target: name must be a non-empty string, got {self.name!r}")
        colors = (self.colors,) if isinstance(self.colors, str) else tuple(self.colors)
        if not all(isinstance(c, str) and c.isidentifier() for c in colors) or len(set(colors)) != len(colors):
            raise ValueError(f"Target {self.name!r}: colors must be distinct identifiers, got {self.colors!r}")
        if len(colors) > 8:
            raise ValueError(f"Target {self.name!r}: at most 8 colour attachments, got {len(colors)}")
        if not colors and not self.depth:
            raise ValueError(f"Target {self.name!r}: give at least one colour attachment or depth=True")
        if self.dtype not in _DTYPES:
            raise ValueError(f"Target {self.name!r}: dtype must be one of {_DTYPES}, got {self.dtype!r}")
        if not (isinstance(self.scale, (int, float)) and 0.0 < self.scale <= 4.0):
            raise ValueError(f"Target {self.name!r}: scale must be in (0, 4], got {self.scale!r}")
        if self.relative not in ("frame", "enclosing"):
            raise ValueError(f"Target {self.name!r}: relative must be 'frame' or 'enclosing', got {self.relative!r}")
        if self.size is not None:
            try:
                w, h = self.size
                ok = all(
                    isinstance(v, (int, np.integer)) and not isinstance(v, bool) and 1 <= v <= 16384 for v in (w, h)
                )
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ValueError(
                    f"Target {self.name!r}: size must be (width, height) in pixels, 1..16384, got {self.size!r}"
                )
            object.__setattr__(self, "size", (int(w), int(h)))
        if isinstance(self.depth, str) and (not self.depth or self.depth == self.name):
            raise ValueError(f"Target {self.name!r}: depth must be True, False or another target's name")
        if self.stencil and self.depth is not True:
            raise ValueError(f"Target {self.name!r}: stencil=True needs depth=True (they share one texture)")
        if self.formats is not None:
            formats = (self.formats,) if isinstance(self.formats, str) else tuple(self.formats)
            if len(formats) != len(colors) or not all(f in FORMATS for f in formats):
                raise ValueError(
                    f"Target {self.name!r}: formats must give one of {sorted(FORMATS)} per colour attachment "
                    f"({len(colors)}), got {self.formats!r}"
                )
            object.__setattr__(self, "formats", formats)
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or not 0 <= self.samples <= 16:
            raise ValueError(f"Target {self.name!r}: samples must be a whole number in [0, 16], got {self.samples!r}")
        if self.samples and self.stencil:
            raise ValueError(f"Target {self.name!r}: multisampled targets have no stencil here; give stencil=False")
        object.__setattr__(self, "colors", colors)
        object.__setattr__(self, "scale", float(self.scale))

    def pixels(self, frame: tuple[int, int]) -> tuple[int, int]:
        """The target's size in pixels for a frame of size ``frame``."""
        if self.size is not None:
            return self.size
        return (max(1, round(frame[0] * self.scale)), max(1, round(frame[1] * self.scale)))

    def format_of(self, attachment: str) -> str:
        """The texel format of colour attachment ``attachment`` (a key of :data:`FORMATS`)."""
        if self.formats is None:
            return self.dtype
        return self.formats[self.colors.index(attachment)]

    def bytes_per_pixel(self) -> int:
        """GPU memory per pixel of the frame: every attachment and depth (4 bytes) times the samples."""
        texels = sum(FORMATS[self.format_of(name)][3] for name in self.colors) + (4 if self.depth is True else 0)
        return texels * max(self.samples, 1)


@dataclass(frozen=True)
class Clear:
    """What a pass clears before drawing: colour (RGBA display values), depth, stencil; None keeps it.

    ``box = (x, y, width, height)`` clears only that pixel rectangle of the bound target (measured from its
    top-left corner, like ``ScissorTest``); None clears all of it.
    """

    color: tuple[float, float, float, float] | None = (0.0, 0.0, 0.0, 0.0)
    depth: float | None = 1.0
    stencil: int | None = None
    box: tuple[int, int, int, int] | None = None

    def __post_init__(self) -> None:
        if self.box is not None:
            try:
                box = tuple(int(v) for v in self.box)
            except (TypeError, ValueError):
                box = ()
            if len(box) != 4 or box[0] < 0 or box[1] < 0 or box[2] <= 0 or box[3] <= 0:
                raise ValueError(f"Clear: box must be (x, y, width, height) pixels, got {self.box!r}")
            object.__setattr__(self, "box", box)
        if self.color is not None:
            object.__setattr__(self, "color", check_rgba("Clear", "color", self.color))
        if self.depth is not None and not (isinstance(self.depth, (int, float)) and 0.0 <= self.depth <= 1.0):
            raise ValueError(f"Clear: depth must be in [0, 1] or None, got {self.depth!r}")
        if self.stencil is not None and (isinstance(self.stencil, bool) or not isinstance(self.stencil, int)):
            raise ValueError(f"Clear: stencil must be a whole number or None, got {self.stencil!r}")


@dataclass(frozen=True)
class Shader:
    """How items are shaded in a pass (overrides of the scene's materials).

    * ``depth_only``: write depth, no colour (shadow maps, depth pre-passes);
    * ``flat_color``: one RGBA colour (display values), no lighting;
    * ``unlit``: each item's own colour (and texture), no lighting;
    * ``vertex``: GLSL defining ``void pass_vertex(inout vec3 world, inout vec3 normal)``,
      called with the world-space position and normal of every vertex;
    * ``fragment``: GLSL defining ``void pass_fragment(inout vec4 color, vec3 P, vec3 N)``,
      called with the final linear colour, the eye-space position and normal;
      it may declare more outputs (``layout(location = 1) out vec4 f_normal;``)
      for targets with several colour attachments;
    * ``uniforms``: values of uniforms the snippets declare;
    * ``defines``: preprocessor features of the engine's own shaders
      (``{"SHADOWS_OFF": True}``, ``{"LIGHT_SELECT": True}``; an inner pass's
      value of a name wins);
    * ``inputs``: sampler uniforms bound to offscreen targets,
      ``{"u_shadow_atlas": ("shadow-atlas", "depth")}`` (texture units 8 and up);
    * ``textures``: sampler uniforms bound to ``om.Texture`` images
      (``{"u_highlight": om.Texture(pattern)}``).
    * ``alpha_cutoff``: fragments whose surface alpha is below it are discarded
      (a depth-only pass of blended surfaces writes depth where they are mostly opaque).
    * ``surface``: GLSL defining ``void pass_surface(Surface s)``, which replaces the
      lighting and the colour output of lit items: it gets the resolved surface (eye
      position and normal, base colour, texel, emission, occlusion, ambient light and
      reflectance, metallic and roughness, material id, see ``shaders.SURFACE``) and
      writes the fragment outputs it declares itself (``layout(location = k) out ...``):
      a G-buffer, a debug view of normals.
    """

    depth_only: bool = False
    flat_color: tuple[float, float, float, float] | None = None
    unlit: bool = False
    vertex: str = ""
    fragment: str = ""
    uniforms: Any = ()
    defines: Any = ()
    inputs: Any = ()
    textures: Any = ()
    alpha_cutoff: float | None = None
    surface: str = ""

    def __post_init__(self) -> None:
        if self.alpha_cutoff is not None and not 0.0 <= float(self.alpha_cutoff) <= 1.0:
            raise ValueError(f"Shader: alpha_cutoff must be in [0, 1] or None, got {self.alpha_cutoff!r}")
        if self.flat_color is not None:
            object.__setattr__(self, "flat_color", check_rgba("Shader", "flat_color", self.flat_color))
        for name in ("vertex", "fragment", "surface"):
            code = getattr(self, name)
            if not isinstance(code, str):
                raise ValueError(f"Shader: {name} must be GLSL source text, got {type(code).__name__}")
        if self.vertex and "pass_vertex" not in self.vertex:
            raise ValueError(
                "Shader: the vertex snippet must define void pass_vertex(inout vec3 world, inout vec3 normal)"
            )
        if self.fragment and "pass_fragment" not in self.fragment:
            raise ValueError(
                "Shader: the fragment snippet must define void pass_fragment(inout vec4 color, vec3 P, vec3 N)"
            )
        if self.surface and "pass_surface" not in self.surface:
            raise ValueError("Shader: the surface snippet must define void pass_surface(Surface s)")
        object.__setattr__(self, "uniforms", uniform_pairs(self.uniforms, "Shader"))
        object.__setattr__(self, "defines", _defines(self.defines))
        object.__setattr__(self, "inputs", _inputs(self.inputs, "Shader"))
        object.__setattr__(self, "textures", _textures(self.textures, "Shader"))


def _textures(values: Any, owner: str) -> tuple[tuple[str, Any], ...]:
    """Sampler textures as (uniform, om.Texture) pairs sorted by uniform."""
    items = values.items() if isinstance(values, Mapping) else values
    textures = []
    for uniform, texture in items:
        if not isinstance(uniform, str) or not uniform.isidentifier() or not hasattr(texture, "image_array"):
            raise ValueError(
                f"{owner}: textures maps sampler names to om.Texture objects, got {uniform!r}: {texture!r}"
            )
        textures.append((uniform, texture))
    return tuple(sorted(textures, key=lambda p: p[0]))


def _defines(values: Any) -> tuple[tuple[str, Any], ...]:
    items = values.items() if isinstance(values, Mapping) else values
    out = []
    for name, value in items:
        if not isinstance(name, str) or not name.isidentifier() or not name.isupper():
            raise ValueError(f"Shader: define names must be upper-case GLSL identifiers, got {name!r}")
        if not isinstance(value, (bool, int, float)):
            raise ValueError(f"Shader: define {name} must be True or a number, got {value!r}")
        out.append((name, value))
    return tuple(sorted(out))


def _inputs(values: Any, owner: str) -> tuple[tuple[str, str, str], ...]:
    """Sampler inputs as sorted (uniform, target name, attachment) triples."""
    items = values.items() if isinstance(values, Mapping) else values
    inputs = []
    for uniform, source in items:
        if not isinstance(uniform, str) or not uniform.isidentifier():
            raise ValueError(f"{owner}: input names must be GLSL identifiers, got {uniform!r}")
        try:
            target, attachment = source
        except (TypeError, ValueError):
            raise ValueError(f"{owner}: input {uniform} must be (target name, attachment), got {source!r}") from None
        inputs.append((uniform, str(target), str(attachment)))
    return tuple(sorted(inputs))


@dataclass(frozen=True)
class FullScreen:
    """An image-space pass: one full-screen triangle shaded by ``fragment``.

    ``fragment`` is GLSL defining ``vec4 effect(vec2 uv)`` (uv in [0, 1],
    origin bottom-left), which returns the colour written (to every colour
    attachment of the target that the snippet does not write itself).
    ``inputs`` maps sampler uniform names to ``(target name, attachment)``:
    an attachment name of that target, or ``"depth"`` (window depth in [0, 1]).
    ``uniforms`` gives other uniform values (sequences: vectors, matrices in
    column order, arrays), ``textures`` maps sampler uniforms to ``om.Texture``
    images bound as stored, without sRGB decoding (data such as a colour
    grading table).  ``label`` names the effect in error messages (its GLSL
    failing to compile).  ``blend=True`` composites the
    result over the target ("over", premultiplied by its alpha) instead of
    replacing it; ``depth=True`` writes ``gl_FragDepth`` from a ``float
    effect_depth(vec2 uv)`` the snippet defines.  ``depth_test`` compares
    that depth with the target's (``"less"``, ``"lequal"``, ... as
    ``om.gl.DepthTest``; ``True`` means ``"lequal"``, so the effect hides
    behind nearer surfaces; None: every fragment passes), so a saved image
    can be merged back by depth (a depth sprite).  The pass's GL ``state`` (a
    ``StencilTest``, a ``ScissorTest``, a ``ColorMask``) applies to the triangle.
    """

    fragment: str
    inputs: Any = ()
    uniforms: Any = ()
    blend: bool = False
    depth: bool = False
    depth_test: str | bool | None = None
    textures: Any = ()
    label: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.fragment, str) or "effect" not in self.fragment:
            raise ValueError("FullScreen: fragment must be GLSL defining vec4 effect(vec2 uv)")
        if self.depth and "effect_depth" not in self.fragment:
            raise ValueError("FullScreen: depth=True needs the snippet to define float effect_depth(vec2 uv)")
        if self.depth_test is True:
            object.__setattr__(self, "depth_test", "lequal")
        elif self.depth_test is False:
            object.__setattr__(self, "depth_test", None)
        if self.depth_test is not None and self.depth_test not in DEPTH_FUNCS:
            raise ValueError(f"FullScreen: depth_test must be None or one of {sorted(DEPTH_FUNCS)}, got "
                             f"{self.depth_test!r}")  # fmt: skip
        if self.depth_test is not None and not self.depth:
            raise ValueError("FullScreen: depth_test compares the effect's depth: give depth=True and effect_depth")
        object.__setattr__(self, "inputs", _inputs(self.inputs, "FullScreen"))
        object.__setattr__(self, "uniforms", uniform_pairs(self.uniforms, "FullScreen"))
        object.__setattr__(self, "textures", _textures(self.textures, "FullScreen"))
        if not isinstance(self.label, str):
            raise ValueError(f"FullScreen: label must be a string, got {self.label!r:.60}")


@dataclass(frozen=True, eq=False)
class Pass:
    """One pass of a GL technique (see the module docstring for every field)."""

    name: str = "pass"
    items: Any = "all"
    mask: str | None = None
    select: Callable[[Any], bool] | None = None
    scopes: Any = True
    source: str = "scope"
    target: Target | None = None
    viewport: tuple[int, int, int, int] | None = None
    clear: Clear | None = None
    state: tuple[Any, ...] = ()
    fallback: tuple[Any, ...] = ()
    camera: Any = None
    front_face: str = "ccw"
    shader: Shader | None = None
    fullscreen: FullScreen | None = None
    custom: Callable[[Any, Any], Any] | None = None
    technique: str | None = None
    _state: tuple[tuple[int, Any], ...] = field(default=(), repr=False)
    _fallback: tuple[tuple[int, Any], ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Pass: name must be a non-empty string, got {self.name!r}")
        object.__setattr__(self, "items", _classes(self.items))
        if self.mask is not None:
            from ...core.mask import compile_mask

            compile_mask(self.mask)  # a syntax error is reported here, with the expression
        if self.front_face not in ("ccw", "cw"):
            raise ValueError(
                f"Pass {self.name!r}: front_face must be 'ccw' or 'cw' (mirrored views), got {self.front_face!r}"
            )
        if self.scopes not in (True, False, "items"):
            raise ValueError(f"Pass {self.name!r}: scopes must be True, False or 'items', got {self.scopes!r}")
        if self.source not in ("scope", "scene"):
            raise ValueError(f"Pass {self.name!r}: source must be 'scope' or 'scene', got {self.source!r}")
        if self.viewport is not None:
            try:
                box = tuple(int(v) for v in self.viewport)
            except (TypeError, ValueError):
                box = ()
            if len(box) != 4 or box[0] < 0 or box[1] < 0 or box[2] <= 0 or box[3] <= 0:
                raise ValueError(
                    f"Pass {self.name!r}: viewport must be (x, y, width, height) pixels, got {self.viewport!r}"
                )
            object.__setattr__(self, "viewport", box)
        if self.select is not None and not callable(self.select):
            raise ValueError(f"Pass {self.name!r}: select must be a function of a draw item, got {self.select!r}")
        for name, kind in (("target", Target), ("clear", Clear), ("shader", Shader), ("fullscreen", FullScreen)):
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                raise ValueError(f"Pass {self.name!r}: {name} must be an om.gl.{kind.__name__}, got {value!r}")
        if self.custom is not None:
            if not callable(self.custom):
                raise ValueError(f"Pass {self.name!r}: custom must be a function (engine, draw), got {self.custom!r}")
            if self.fullscreen is not None:
                raise ValueError(f"Pass {self.name!r}: give custom or fullscreen, not both")
        if self.technique not in TECHNIQUES:
            raise ValueError(f"Pass {self.name!r}: technique must be one of {TECHNIQUES}, got {self.technique!r}")
        object.__setattr__(self, "_state", self._captured("state"))
        object.__setattr__(self, "_fallback", self._captured("fallback"))
        if self.camera is not None:
            object.__setattr__(self, "camera", pass_camera(self.camera, self.name))

    def _captured(self, name: str) -> tuple[tuple[int, Any], ...]:
        from .attributes import GLState

        values = getattr(self, name)
        if isinstance(values, GLState) or (
            isinstance(values, tuple) and len(values) == 2 and isinstance(values[0], type)
        ):
            values = (values,)
        out = []
        for attribute in values:
            if isinstance(attribute, tuple) and len(attribute) == 2 and isinstance(attribute[0], type):
                kind, value = attribute  # a derived kind's value, e.g. (FillMode, True) for wireframe
                if getattr(kind, "index", -1) < 0:
                    raise ValueError(f"Pass {self.name!r}: {kind!r} is not a registered GL state kind")
                out.append((kind.index, value))
                continue
            if not isinstance(attribute, GLState):
                raise ValueError(
                    f"Pass {self.name!r}: {name} takes GL state attributes (om.gl.CullFace(...), om.gl.DepthMask(...)"
                    f", ...) or (state kind, value) pairs, got {attribute!r}"
                )
            out.append((type(attribute).index, attribute.capture()))
        object.__setattr__(self, name, tuple(values))
        return tuple(out)

    @property
    def state_values(self) -> tuple[tuple[int, Any], ...]:
        """The GL state the pass sets, as (state kind index, captured value) pairs in order."""
        return self._state

    def scissored(self, box: tuple[int, int, int, int], name: str | None = None) -> Pass:
        """This pass limited to the pixel rectangle ``box`` (x, y, width, height from the target's top-left
        corner): its ``ScissorTest`` is ``box`` and its clear, if any, clears only ``box``; ``name`` renames it.

        A copy made without checking the rest of the description again: what a
        technique that redraws a changed rectangle every frame (shadow maps'
        partial updates) derives from a pass it made once.
        """
        from .attributes import ScissorTest

        clear = self.clear
        if clear is not None:
            clear = Clear(color=clear.color, depth=clear.depth, stencil=clear.stencil, box=box)  # box checked
        elif not (len(box) == 4 and all(isinstance(v, int) for v in box) and min(box) >= 0 < min(box[2:])):
            raise ValueError(f"Pass {self.name!r}: a scissor box is (x, y, width, height) pixels, got {box!r}")
        index = ScissorTest.index
        fields = dict(self.__dict__)  # frozen: the copy's fields are set here, before it is made
        if self._state and any(v[0] == index for v in self._state):
            kept = [(k, v) for k, v in zip(self.state, self._state, strict=True) if v[0] != index]
            fields["state"], fields["_state"] = tuple(k for k, _ in kept), tuple(v for _, v in kept)
        fields["state"] = fields["state"] + ((ScissorTest, tuple(box)),)
        fields["_state"] = fields["_state"] + ((index, tuple(box)),)
        fields["clear"] = clear
        if name is not None:
            fields["name"] = name
        out = object.__new__(Pass)
        out.__dict__.update(fields)
        return out

    def key(self) -> tuple:
        """The description as a comparable value (what the engine compares frame by frame)."""
        camera = None if self.camera is None else (self.camera[0].tobytes(), self.camera[1].tobytes())
        return (
            self.name,
            self.items,
            self.mask,
            self.select,
            self.scopes,
            self.source,
            self.target,
            self.viewport,
            self.clear,
            self._state,
            self._fallback,
            camera,
            self.front_face,
            self.shader,
            self.fullscreen,
            self.custom,
            self.technique,
        )

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Pass) and self.key() == other.key()

    def __hash__(self) -> int:
        return hash(self.key())


def pass_camera(value: Any, name: str) -> tuple[np.ndarray, np.ndarray | None]:
    """(view, projection or None) from an om.Camera (projection made per frame aspect) or two matrices."""
    from ...core.camera import Camera

    if isinstance(value, Camera):
        return (np.asarray(value.view_matrix(), dtype=np.float64), value)  # type: ignore[return-value]
    try:
        view, proj = value
        view = np.asarray(view, dtype=np.float64)
        proj = np.asarray(proj, dtype=np.float64)
    except (TypeError, ValueError):
        view = proj = None
    if view is None or view.shape != (4, 4) or proj.shape != (4, 4):  # type: ignore[union-attr]
        raise ValueError(f"Pass {name!r}: camera must be an om.Camera or (view, projection) 4x4 matrices")
    if not (np.all(np.isfinite(view)) and np.all(np.isfinite(proj))):  # type: ignore[arg-type]
        raise ValueError(f"Pass {name!r}: camera matrices must be finite")
    return view, proj  # type: ignore[return-value]


#: The pass a frame starts with: every item, the frame's target and camera.
FRAME = Pass("frame")


class Composed:
    """A pass composed with the passes enclosing it: what the renderer actually applies to items."""

    __slots__ = ("classes", "masks", "selects", "scopes", "state", "fallback", "camera", "shader", "names")

    def __init__(self) -> None:
        self.classes: frozenset[str] = _ALL
        self.masks: tuple[str, ...] = ()
        self.selects: tuple[Callable[[Any], bool], ...] = ()
        self.scopes = True
        self.state: dict[int, Any] = {}
        self.fallback: dict[int, Any] = {}
        self.camera: Any = None
        self.shader: tuple[Shader, ...] = ()
        self.names: tuple[str, ...] = ()

    def then(self, inner: Pass) -> Composed:
        """This composition narrowed by ``inner``."""
        out = Composed()
        out.classes = self.classes & inner.items
        out.masks = self.masks + ((inner.mask,) if inner.mask else ())
        out.selects = self.selects + ((inner.select,) if inner.select is not None else ())
        out.scopes = inner.scopes
        out.state = {**self.state, **dict(inner._state)}
        out.fallback = {**self.fallback, **dict(inner._fallback)}
        out.camera = inner.camera if inner.camera is not None else self.camera
        out.shader = self.shader + ((inner.shader,) if inner.shader is not None else ())
        out.names = (*self.names, inner.name)
        return out

    def raster(self, values: tuple[Any, ...], defaults: tuple[Any, ...]) -> tuple[Any, ...]:
        """An item's raster values with this pass's overrides (forced) and fallbacks (where at the default)."""
        if not self.state and not self.fallback:
            return values
        out = list(values)
        for index, value in self.fallback.items():
            if out[index] == defaults[index]:
                out[index] = value
        for index, value in self.state.items():
            out[index] = value
        return tuple(out)

    def shading(self) -> tuple[tuple[str, Any], ...]:
        """Program features of the shader overrides (innermost setting wins; snippets accumulate)."""
        depth_only = unlit = False
        flat = None
        vertex: list[str] = []
        fragment: list[str] = []
        surface = ""
        cutoff = None
        for s in self.shader:
            if s.surface:
                surface = s.surface
            if s.alpha_cutoff is not None:
                cutoff = float(s.alpha_cutoff)
            depth_only = depth_only or s.depth_only
            unlit = unlit or s.unlit
            if s.flat_color is not None:
                flat = s.flat_color
            if s.vertex:
                vertex.append(s.vertex)
            if s.fragment:
                fragment.append(s.fragment)
        out: list[tuple[str, Any]] = []
        if depth_only:
            out.append(("DEPTH_ONLY", True))
        elif flat is not None:
            out.append(("FLAT_COLOR", True))
        elif unlit:
            out.append(("UNLIT", True))
        if vertex:
            out.append(("PASS_VERTEX", tuple(vertex)))
        if fragment and not depth_only:
            out.append(("PASS_FRAGMENT", tuple(fragment)))
        if surface and not depth_only:
            out.append(("PASS_SURFACE", surface))
        defines: dict[str, Any] = {}
        for s in self.shader:
            defines.update(s.defines)
        out.extend((name, value) for name, value in sorted(defines.items()) if value is not False)
        if cutoff is not None:
            out.append(("PASS_ALPHA_CUTOFF", cutoff))
        return tuple(out)

    def inputs(self) -> dict[str, Any]:
        """Sampler inputs of the shader overrides: uniform -> (target name, attachment) or an om.Texture."""
        out: dict[str, Any] = {}
        for s in self.shader:
            for uniform, target, attachment in s.inputs:
                out[uniform] = (target, attachment)
            for uniform, texture in s.textures:
                out[uniform] = texture
        return out

    def uniforms(self) -> dict[str, Any]:
        """Uniform values of the shader overrides (the flat colour among them, linear)."""
        values: dict[str, Any] = {}
        for s in self.shader:
            values.update(dict(s.uniforms))
            if s.flat_color is not None:
                from ...attributes.photometry import linear_rgb

                values["u_flat_color"] = (*linear_rgb(s.flat_color), s.flat_color[3])
        return values
