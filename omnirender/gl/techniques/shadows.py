"""Shadow maps in the GL engine: on by default, as in the offline engines.

Every frame whose scene has lights with ``casts_shadows`` starts with the
shadow-map passes (:class:`ShadowPlan`): one depth-only pass per map face into
a single depth atlas (a comparison texture), drawing every opaque item of the
scene that casts shadows (``om.Shadowing(cast=...)``), nested technique
scopes included, from the light's camera:

* directional lights: an orthographic camera fitted to the bounds of the
  shadow casters;
* spot lights: a perspective camera over the cone (cut-off up to 65 degrees;
  wider spots are treated as point lights);
* point lights: six 90-degree faces of a cube; faces that cannot see a caster
  are not drawn.

Perspective faces are fitted tightly: each is cropped to the rectangle the
casters' bounds cover in it (:func:`frustum_crop`), so its texels go where
shadows can fall.  The map resolution follows the image (``resolution=None``:
the image's larger side, :func:`auto_resolution`) within an atlas
budget (:data:`MAX_ATLAS`), so a shadow texel stays near a pixel on the
screen (1024 texels at 640x480); both depend on the casters, the lights and the image size only, never
on the camera, so maps drawn once stay valid while the camera moves.

Lit shaders then look each light up in its face (``SHADOW_MAPS``, see
:mod:`.shadow_glsl`) with percentage-closer filtering (by default a tent over
3x3 texels: edges without stair steps), slope-scaled normal offset and depth
bias, for every item that receives shadows.  :class:`ShadowMaps` is the
technique that sets these for the subgraph after it: ``ShadowMaps(enabled=False)``
at the top of the root node switches shadow maps off for the whole frame (no
map is drawn), elsewhere it keeps shadows off the subgraph; ``softness``,
``bias`` and ``normal_offset`` apply to the receivers it scopes; the first
ShadowMaps of the scene sets the map ``resolution``.  ``GLEngine(shadows=False)``
turns them off for every frame.  Other engines ignore the technique (they
always have shadows).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from ...core import version_key
from ...core.camera import look_at_matrix, orthographic_matrix, perspective_matrix
from ..engine.attributes import ScissorTest
from ..engine.drawlist import Batch, Scope, Segment, world_bounds
from ..engine.passes import Clear, Pass, Shader, Target
from ..engine.shadow_glsl import MAX_SHADOW_FACES, pcf_mode
from ..engine.stages import FrameStage
from ..engine.state import casts_shadows
from ..engine.technique import GLTechnique
from ..engine.units import SHADOW_ATLAS

__all__ = [
    "ShadowMaps",
    "ShadowPlan",
    "ShadowMapStage",
    "ATLAS",
    "SHADOW_UNIT",
    "caster_bounds",
    "auto_resolution",
    "frustum_crop",
    "fit_bounds",
    "MAX_ATLAS",
    "PARTIAL_MAX",
]

#: Name of the frame's shadow-map atlas target.
ATLAS = "shadow-atlas"
#: Texture unit of the atlas (the table of units: ``engine/units.py``).
SHADOW_UNIT = SHADOW_ATLAS
#: Cube faces of a point light: the axis each looks along, and its up vector.
_CUBE = (
    ((1, 0, 0), (0, -1, 0)),
    ((-1, 0, 0), (0, -1, 0)),
    ((0, 1, 0), (0, 0, 1)),
    ((0, -1, 0), (0, 0, -1)),
    ((0, 0, 1), (0, -1, 0)),
    ((0, 0, -1), (0, -1, 0)),
)
#: Spots wider than this get a cube of faces: one perspective map would stretch too far.
_MAX_SPOT_CUTOFF = 65.0
#: The atlas's largest side in texels (the faces of a frame share it: 4096^2 depth texels are 64 MiB).
MAX_ATLAS = 4096
#: Automatic map resolutions: texels per pixel of the image's larger side, and the range.
AUTO_TEXELS_PER_PIXEL = 1.0
AUTO_RANGE = (512, 2048)
#: Cropped faces keep this margin (a fraction of the crop) around the casters' rectangle.
_CROP_MARGIN = 0.02


def auto_resolution(size: tuple[int, int]) -> int:
    """The map resolution for an image of ``size``: its larger side, a power of two in ``AUTO_RANGE``."""
    want = AUTO_TEXELS_PER_PIXEL * max(int(size[0]), int(size[1]), 1)
    r = 1 << max(int(math.ceil(math.log2(want))), 0)
    return int(min(max(r, AUTO_RANGE[0]), AUTO_RANGE[1]))


def _positive(owner: str, name: str, value: Any, minimum: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < minimum:
        raise ValueError(f"{owner}: {name} must be a number >= {minimum}, got {value!r}")
    return float(value)


class ShadowMaps(GLTechnique):
    """Shadow-map settings for the subgraph after it (GL; other engines ignore it).

    ``enabled=False`` keeps shadow maps off these receivers (at the top of the
    root node: off for the whole frame).  ``resolution`` (pixels per map
    side; None: :func:`auto_resolution` of the image) is taken from the
    scene's first ShadowMaps.  ``softness`` is the
    width of percentage-closer filtering in map texels (0: hard shadows, 1:
    bilinear, 2: a tent over 3x3 texels, more: four bilinear taps spread wider),
    ``bias`` the depth bias and ``normal_offset`` the offset along the
    surface normal, both in map texels: they keep lit surfaces from shadowing
    themselves (acne) without detaching shadows from their casters
    (peter-panning).
    """

    __slots__ = ("enabled", "resolution", "softness", "bias", "normal_offset")
    #: its one pass is data made from its fields (a shader's uniforms and defines): a steady frame may replay it
    #: (``gl/engine/plan.py``); a changed field counts a version, and the frame after it is drawn in full
    replayable = True

    @property
    def deferred_inline(self) -> bool:
        """Whether the deferred pipeline shades what it scopes through the G-buffer (with the frame's filter and
        bias): yes while it receives shadows; ``enabled=False`` keeps its subgraph in the forward passes."""
        return self.enabled

    def __init__(
        self,
        enabled: bool = True,
        resolution: int | None = None,
        softness: float = 2.0,
        bias: float = 2.0,
        normal_offset: float = 3.0,
    ) -> None:
        super().__init__(passes=1)
        if not isinstance(enabled, bool):
            raise ValueError(f"ShadowMaps: enabled must be True or False, got {enabled!r}")
        if resolution is not None and (
            isinstance(resolution, bool) or not isinstance(resolution, int) or not 16 <= resolution <= 8192
        ):
            raise ValueError(
                f"ShadowMaps: resolution must be None (automatic) or a whole number of pixels in [16, 8192], "
                f"got {resolution!r}"
            )
        self.enabled = enabled
        self.resolution = resolution
        self.softness = _positive("ShadowMaps", "softness", softness)
        self.bias = _positive("ShadowMaps", "bias", bias)
        self.normal_offset = _positive("ShadowMaps", "normal_offset", normal_offset)

    def style(self) -> tuple[float, float, float]:
        """The ``u_shadow_style`` uniform: softness, bias, normal offset (texels)."""
        return (self.softness, self.bias, self.normal_offset)

    def prepare_pass(self, engine: Any) -> None:
        if self.enabled:
            shader = Shader(uniforms={"u_shadow_style": self.style()}, defines={"SHADOW_PCF": pcf_mode(self.softness)})
        else:
            shader = Shader(defines={"SHADOWS_OFF": True})
        engine.set_pass(Pass("shadows" if self.enabled else "no-shadows", shader=shader))


class _Face:
    """One map of the atlas: a light camera (view, projection), its tile, texel size, whether it is drawn."""

    __slots__ = ("view", "proj", "texel", "drawn", "tile", "matrix", "rows", "ortho", "signature", "template",
                 "every", "recorded")  # fmt: skip

    def __init__(self, view: np.ndarray, proj: np.ndarray, texel: tuple[float, float], drawn: bool = True) -> None:
        self.view, self.proj, self.texel, self.drawn = view, proj, texel, drawn
        self.tile: tuple[int, int] | None = None  # (column, row) in the atlas
        #: the light camera's projection @ view, and as rows of Python floats (a few boxes are projected with them)
        self.matrix = proj @ view
        self.rows: list[list[float]] = self.matrix.tolist()
        m = self.matrix
        self.ortho = bool(m[3, 0] == 0.0 and m[3, 1] == 0.0 and m[3, 2] == 0.0)
        #: what its texels depend on (:func:`_signature`, set with its tile) and its partial passes' pattern
        self.signature = b""
        self.template: Pass | None = None
        #: (the full passes' select, the pattern of its partial passes that draw every caster) (_every_caster_pass)
        self.every: tuple[Any, Pass] | None = None
        #: the draws of its last partial pass that drew every caster, recorded (``FrameRunner.run_recorded``)
        self.recorded: Any = None


class _MapPasses(GLTechnique):
    """The depth passes that draw a frame's shadow maps (run by the engine before its technique)."""

    __slots__ = ("descriptions",)

    def __init__(self, descriptions: list[Pass]) -> None:
        super().__init__(passes=len(descriptions))
        object.__setattr__(self, "descriptions", tuple(descriptions))

    def prepare_pass(self, engine: Any) -> None:
        engine.set_pass(self.descriptions[engine.current_pass])


class ShadowPlan:
    """The shadow maps of one frame: faces per light, the atlas, the passes and the shader uniforms."""

    def __init__(
        self,
        settings: ShadowMaps,
        lights: list[tuple[Any, np.ndarray]],
        bounds: Any,
        size: tuple[int, int] = (640, 480),
    ) -> None:
        self.settings = settings
        self.faces: list[_Face] = []
        #: id(light) -> (first face, face count)
        self.light_faces: dict[int, tuple[int, int]] = {}
        lo, hi = bounds
        wanted = settings.resolution if settings.resolution is not None else auto_resolution(size)
        for light, matrix in lights:
            faces = _light_faces(light, matrix, lo, hi, wanted)
            if not faces:
                continue
            if len(self.faces) + len(faces) > MAX_SHADOW_FACES:
                warnings.warn(
                    f"GLEngine: more than {MAX_SHADOW_FACES} shadow-map faces (a point light takes 6); the shadows "
                    "of the remaining lights are left out; set casts_shadows=False on lights that need none",
                    stacklevel=4,
                )
                break
            self.light_faces[id(light)] = (len(self.faces), len(faces))
            self.faces.extend(faces)
        drawn = [f for f in self.faces if f.drawn]
        cols = max(1, math.ceil(math.sqrt(len(drawn))))
        rows = max(1, math.ceil(len(drawn) / cols))
        r = wanted if settings.resolution is not None else min(wanted, MAX_ATLAS // cols)
        self.resolution = r
        if r != wanted:  # texel sizes were measured for the wanted resolution
            for face in self.faces:
                face.texel = (face.texel[0] * wanted / r, face.texel[1] * wanted / r)
        self.target = Target(ATLAS, colors=(), depth=True, size=(cols * r, rows * r))
        for k, face in enumerate(drawn):
            face.tile = (k % cols, k // cols)
            face.signature = _signature(face, r)
        self.cols, self.rows = cols, rows
        self._arrays()

    def __len__(self) -> int:
        return len(self.faces)

    def features(self) -> tuple[tuple[str, Any], ...]:
        """The program features of a receiver in this frame (a ShadowMaps pass may override the filter)."""
        return (("SHADOW_MAPS", len(self.faces)), ("SHADOW_PCF", pcf_mode(self.settings.softness)))

    def technique(self, select: Any = casts_shadows) -> _MapPasses | None:
        """The depth passes, or None when no face needs drawing (``select``: the items they draw; None: every
        opaque item, for a draw list whose opaque items all cast shadows)."""
        r = self.resolution
        passes = []
        for k, face in enumerate(self.faces):
            if face.tile is None:
                continue
            col, row = face.tile
            passes.append(
                Pass(
                    f"shadow-map[{k}]",
                    items="opaque",
                    select=select,
                    scopes="items",
                    source="scene",
                    target=self.target,
                    viewport=(col * r, row * r, r, r),
                    clear=Clear(color=None, depth=1.0) if not passes else None,
                    camera=(face.view, face.proj),
                    shader=Shader(depth_only=True),
                )
            )
        return _MapPasses(passes) if passes else None

    def _arrays(self) -> None:
        n = len(self.faces)
        self.matrices = np.zeros((n, 4, 4), np.float32)
        self.tiles = np.zeros((n, 4), np.float32)
        self.texels = np.zeros((n, 2), np.float32)
        for k, face in enumerate(self.faces):
            self.matrices[k] = face.matrix.T
            self.texels[k] = face.texel
            if face.tile is not None:
                col, row = face.tile
                r = self.resolution
                self.tiles[k] = (col * r, row * r, r, r)
        self.style = np.asarray(self.settings.style(), np.float32)
        #: (uniform, array length, ids of the light order for u_lshadow) -> the bytes written (:meth:`apply`)
        self._bytes: dict[tuple[str, int, tuple[int, ...]], bytes] = {}

    def light_array(self, order: list[Any], size: int) -> np.ndarray:
        """``u_lshadow``: (first face, count, 0, 0) for the lights of a light-uniform set, in its order."""
        out = np.zeros((size, 4), np.float32)
        for i, light in enumerate(order[:size]):
            found = self.light_faces.get(id(light))
            if found is not None:
                out[i, :2] = found
        return out

    def apply(self, program: Any, atlas: Any, order: list[Any]) -> None:
        """Bind the atlas and write the shadow uniforms a program reads."""
        atlas.use(SHADOW_UNIT)
        program["u_shadow_atlas"].value = SHADOW_UNIT
        made = self._bytes
        for name in ("u_shadow_mat", "u_shadow_tile", "u_shadow_texel", "u_shadow_style", "u_lshadow"):
            u = program.get(name, None)
            if u is None:
                continue
            # the compiler may trim arrays to the elements a variant reads; the bytes are made once per length
            key = (name, u.array_length, tuple(map(id, order)) if name == "u_lshadow" else ())
            data = made.get(key)
            if data is None:
                if name == "u_lshadow":
                    data = self.light_array(order, u.array_length).tobytes()
                else:
                    array = {"u_shadow_mat": self.matrices, "u_shadow_tile": self.tiles,
                             "u_shadow_texel": self.texels, "u_shadow_style": self.style}[name]  # fmt: skip
                    data = array[: u.array_length].tobytes() if array.ndim > 1 else array.tobytes()
                made[key] = data
            u.write(data)


def frame_settings(root: Scope | None, enabled: bool) -> ShadowMaps | None:
    """The frame's shadow-map settings: the scene's first ShadowMaps, else the defaults; None when off."""
    if not enabled or root is None:
        return None
    from .shadow_volumes import ShadowVolumes

    if len(root.entries) == 1 and isinstance(root.entries[0], Scope):
        if isinstance(root.entries[0].technique, ShadowVolumes):
            return None  # the whole scene has exact shadow volumes: no maps needed
    for scope in root.walk():
        if isinstance(scope.technique, ShadowMaps):
            whole = len(root.entries) == 1 and root.entries[0] is scope
            if not scope.technique.enabled and whole:
                return None
            return scope.technique
    return _DEFAULT


_DEFAULT = ShadowMaps()


def caster_bounds(root: Scope) -> tuple[np.ndarray, np.ndarray] | None:
    """World (min, max) of the items that cast shadows, or None when there are none."""
    return world_bounds(item for item in root.all_items() if not item.transparent and casts_shadows(item))


class ShadowMapStage(FrameStage):
    """The frame stage that draws the shadow-map atlas (before the frame technique, whose lit shaders read it).

    The maps follow changes (the camera is free to move): a face of the atlas
    is kept while its light camera and tile are the ones it was drawn with and
    no caster changed inside it.  The render index's caster journal says which
    casters' boxes changed (old and new places; a row that left and came back
    in the same place, e.g. a replaced ``Material``, cancels out): the region
    they cover in a face (in texels, one texel of margin) is cleared under a
    scissor and only the casters whose boxes meet it are drawn into it again
    (:data:`PARTIAL_MAX` of the face or less; more is redrawn in full).  The
    faces are fitted to the casters' bounds snapped outward to a grid
    (:func:`fit_bounds`), so a move that stays inside it keeps every face's
    projection; one that leaves it redraws the faces in full.

    ``engine.stats["shadow_maps"]`` says what each frame did: ``full``,
    ``partial`` and ``kept`` (faces), ``pixels`` (texels redrawn by partial
    updates), ``regions`` (face index, (x, y, width, height) atlas texels from
    the bottom-left corner, of each partial update) and ``replayed`` (faces whose
    update issued a recorded pass's draws again: where a partial update draws
    every caster, before a recorded frame is replayed, the face's pass is
    recorded once and replayed under each new region's scissor,
    ``FrameRunner.replay_draws``).

    It forgets nothing when placements change (no :meth:`changed`): the
    engine's render index keeps the casters' bounds and journal up to date.
    """

    name = "shadow maps"

    #: how a partial update draws the region of a face: True picks the casters whose boxes meet it (their rows
    #: copied into a batch of their own: what a software rasteriser, which pays for every vertex, needs); False
    #: draws every caster under the region's scissor (one draw per batch, nothing picked per row: what a GPU,
    #: which clips what the scissor rejects for nearly nothing, needs); None (the default) decides by the GL
    #: renderer (llvmpipe, softpipe: True; else False)
    partial_picks: bool | None = None

    def __init__(self) -> None:
        #: (key, plan, its technique, the select it was made with, the inputs (_memo) and fit it was found for)
        self._cache: Any = None
        #: what the atlas holds: its description and, per tile, the signature of the face drawn into it
        self._atlas: Target | None = None
        self._held: dict[tuple[int, int], bytes] = {}
        #: id(batch) -> (batch, the batch of its rows a partial update draws)
        self._scratch: dict[int, tuple[Any, Batch]] = {}
        #: (face signature, id(batch)) -> _Rects: the casters' rectangles in a face, following the journal
        self._rects: dict[tuple[bytes, int], _Rects] = {}
        #: (root, index version, the full passes' select) of the last structure looked at (:meth:`_select`)
        self._selected: tuple[Any, int, Any] | None = None
        #: (the casters' bounds, the bounds fitted to them) of the last frame
        self._fitted: tuple[Any, np.ndarray, np.ndarray] | None = None
        #: (root, index version, engine.shadows, declarations, size, (component, version) of the settings and
        #: lights, settings, lights) of the last frame (:meth:`_inputs`)
        self._memo: tuple[Any, ...] | None = None

    def replayable(self, engine: Any) -> bool:
        """What it draws follows the draw list, lights and settings: a frame whose atlas faces were all kept
        may be replayed (the atlas stays; its bind and uniforms are recorded with the draws); a frame that
        draws a face is not recorded (the map passes' technique is not replayable)."""
        return True

    def follows_rows(self, engine: Any) -> bool:
        """The maps follow moved casters (:meth:`follow_rows` before the replay of a recorded frame)."""
        return True

    def follows_plan(self, plan: Any) -> bool:
        """Only a recorded frame that drew shadow maps has maps to follow."""
        return plan.stats.get("shadow_plan") is not None

    def follow_rows(self, frame: Any, root: Scope, plan: Any) -> bool:
        """Before the replay of a recorded frame after rows moved in place: the maps follow the moved casters
        (the regions their old and new boxes cover, as :meth:`draw` does); the plan holds while the faces are
        the ones it was recorded with (the same light cameras and tiles: the same uniforms), i.e. the
        casters' fitted bounds held."""
        recorded = plan.stats.get("shadow_plan")
        if recorded is None:  # the recorded frame drew no maps: there are none to follow
            return True
        self.draw(frame, root)
        return frame.state.shadow_plan is recorded

    def release(self) -> None:
        for _, batch in self._scratch.values():
            batch.release()
        self._scratch.clear()

    def _picks(self, engine: Any) -> bool:
        """Whether partial updates pick the casters meeting the region (:attr:`partial_picks`)."""
        picks = self.partial_picks
        if picks is None:
            picks = self.partial_picks = software_rasterizer(engine.ctx)
        return picks

    def _select(self, engine: Any, root: Scope) -> Any:
        """The full passes' item predicate: ``casts_shadows``, or None when every opaque batch of the draw list
        casts shadows (then they draw the scene's own batches, not copies that the predicate filters: nothing
        to keep up to date when rows move, leave or come)."""
        index = engine.index
        found = self._selected
        if found is not None and found[0] is root and found[1] == index.version:
            return found[2]
        select = None
        for scope in root.walk():
            if scope.parts is None:
                select = casts_shadows
                break
            batches = (b for part in scope.parts if isinstance(part, Segment) for b in part.batches)
            if not all(casts_shadows(b) for b in batches if len(b.rows) or b.items):
                select = casts_shadows
                break
        self._selected = (root, index.version, select)
        return select

    def _inputs(self, engine: Any, root: Scope, installed: bool) -> tuple[ShadowMaps | None, list[Any]]:
        """The frame's shadow-map settings (:func:`frame_settings`) and its lights that cast shadows with their
        matrices; kept while the draw list (root, index version), the engine's switch, the pre-evaluated
        declarations, the image size and the versions of the settings and lights hold."""
        memo = self._memo
        if (
            installed
            and memo is not None
            and memo[0] is root
            and memo[1] == engine.index.version
            and memo[2] == engine.shadows
            and memo[3] is engine.declared
            and memo[4] == engine.size
            and all(component.version == version for component, version in memo[5])
        ):
            return memo[6], memo[7]
        settings = frame_settings(root if installed else None, engine.shadows)
        lights = [(light, m) for light, m in engine.scene_lights if getattr(light, "casts_shadows", False)]
        versions = tuple((c, c.version) for c in (settings, *(light for light, _ in lights)) if c is not None)
        self._memo = (root, engine.index.version, engine.shadows, engine.declared, tuple(engine.size), versions,
                      settings, lights) if installed else None  # fmt: skip
        return settings, lights

    def _forget(self) -> int:
        self._atlas = None
        self._held = {}
        self._rects = {}
        return 0

    def _follow(self, changes: list[Any] | None, signatures: set[bytes]) -> None:
        """The cached caster rectangles follow the journal's changes (all forgotten when it cannot say)."""
        if changes is None:
            self._rects = {}
            return
        if any(key[0] not in signatures for key in self._rects):
            self._rects = {key: rects for key, rects in self._rects.items() if key[0] in signatures}
        if not changes or not self._rects:
            return
        by_batch: dict[int, list[_Rects]] = {}
        for (_, batch_id), rects in self._rects.items():
            by_batch.setdefault(batch_id, []).append(rects)
        for change in changes:
            for rects in by_batch.get(id(change.batch), ()):
                rects.follow(change)

    def draw(self, frame: Any, root: Scope) -> int:
        engine = frame.engine
        report = {"full": 0, "partial": 0, "kept": 0, "pixels": 0, "regions": [], "replayed": 0}
        engine.stats["shadow_maps"] = report
        installed = engine.root_scope is not None
        changes = engine.index.take_caster_changes() if installed else None
        settings, lights = self._inputs(engine, root, installed)
        if settings is None or not lights:
            return self._forget()
        bounds = engine.index.caster_bounds()[0] if installed else caster_bounds(root)
        if bounds is None:
            return self._forget()
        fitted = self._fitted
        if fitted is None or fitted[0] is not bounds:  # the index keeps the bounds while they hold
            fitted = self._fitted = (bounds, *fit_bounds(*bounds))
        lo, hi = fitted[1], fitted[2]
        cached = self._cache
        if cached is not None and self._memo is not None and cached[4] is self._memo and cached[5] is fitted:
            plan = cached[1]  # the same inputs as the frame before: the same key
        else:
            key = (version_key(settings), lo.tobytes(), hi.tobytes(),
                   tuple((light, light.version, m.tobytes()) for light, m in lights), tuple(engine.size))  # fmt: skip
            plan = cached[1] if cached is not None and cached[0] == key else None
            if plan is not None:
                cached = self._cache = (key, plan, cached[2], cached[3], self._memo, fitted)
        select = self._select(engine, root) if installed else casts_shadows
        if plan is None or self._cache[3] is not select:
            key = (version_key(settings), lo.tobytes(), hi.tobytes(),
                   tuple((light, light.version, m.tobytes()) for light, m in lights), tuple(engine.size))  # fmt: skip
            plan = ShadowPlan(settings, lights, (lo, hi), tuple(engine.size)) if plan is None else plan
            self._cache = (key, plan, plan.technique(select), select, self._memo, fitted)
        technique = self._cache[2]
        if technique is None:
            return self._forget()
        frame.state.shadow_plan = plan
        faces = [(k, face) for k, face in enumerate(plan.faces) if face.tile is not None]
        held = self._held if self._atlas == plan.target and frame.keep_target(plan.target) else {}
        self._atlas, self._held = plan.target, {face.tile: face.signature for _, face in faces}
        self._follow(changes, set(self._held.values()))
        if not held:  # a new atlas: every face, under one clear
            report["full"] = len(faces)
            return frame.run(technique, root)
        full: list[tuple[int, _Face]] = []
        partial: list[tuple[int, _Face, tuple[int, int, int, int]]] = []
        boxes = None if changes is None else _changed_boxes(changes)
        for k, face in faces:
            if held.get(face.tile) != self._held[face.tile] or boxes is None:
                full.append((k, face))
                continue
            region = _face_region(face, plan.resolution, *boxes) if len(boxes[0]) else None
            if region is None:
                report["kept"] += 1
            elif region[2] * region[3] > PARTIAL_MAX * plan.resolution**2:
                full.append((k, face))
            else:
                partial.append((k, face, region))
        calls = 0
        if full:
            if frame.state.recorder is None and not self._picks(engine):  # (between a recorded frame's passes)
                r = plan.resolution  # a whole tile is the every-caster pass under the tile's scissor
                calls += self._draw_every(frame, root, plan, [(k, face, (0, 0, r, r)) for k, face in full], select,
                                          report)  # fmt: skip
            else:
                calls += frame.run(_MapPasses([_face_pass(plan, k, face, select) for k, face in full]), root)
            report["full"] = len(full)
        if partial:
            calls += self._draw_partial(frame, root, plan, partial, select, report)
        return calls

    def _draw_partial(
        self, frame: Any, root: Scope, plan: ShadowPlan, partial: list[tuple[int, _Face, tuple[int, int, int, int]]],
        select: Any, report: dict[str, Any],
    ) -> int:  # fmt: skip
        """Redraw the changed ``region`` of each ``(k, face, region)`` of ``partial`` (:attr:`partial_picks`: the
        casters meeting it picked, or every caster under its scissor); returns the draw calls."""
        engine = frame.engine
        calls = 0
        picks = self._picks(engine)
        if not picks:  # every caster drawn under the regions' scissors, nothing picked
            calls = self._draw_every(frame, root, plan, partial, select, report)
        casters = engine.index.caster_boxes() if picks and engine.root_scope is not None else None
        for k, face, region in partial:
            if picks:
                if casters is None:  # some caster is not in a batch: the face is drawn in full
                    calls += frame.run(_MapPasses([_face_pass(plan, k, face, select)]), root)
                    report["full"] += 1
                    continue
                scope = self._casters_in(casters, face, face.signature, plan.resolution, region)
                calls += frame.run(_MapPasses([_partial_pass(plan, k, face, region)]), scope)
            col, row = face.tile
            r = plan.resolution
            report["partial"] += 1
            report["pixels"] += region[2] * region[3]
            report["regions"].append((k, (col * r + region[0], row * r + region[1], region[2], region[3])))
        return calls

    def _draw_every(
        self, frame: Any, root: Scope, plan: ShadowPlan, partial: list[tuple[int, _Face, tuple[int, int, int, int]]],
        select: Any, report: dict[str, Any],
    ) -> int:  # fmt: skip
        """Redraw the regions of ``partial`` drawing every caster under each region's scissor; returns the draw
        calls.  Between the frame's own passes (``follow_rows``, before a recorded frame is replayed) a face's
        pass is recorded once and its draws issued again under each new region's scissor
        (``FrameRunner.replay_draws``: no pass, technique or drawer work per frame) while the casters' batches
        and their draws hold; ``report["replayed"]`` counts those.  A region of a whole tile redraws the face
        in full (the every-caster pass is the face's full pass under its tile's scissor)."""
        if frame.state.recorder is not None:  # inside a frame being recorded: the passes as they are
            return frame.run(_MapPasses([_every_caster_pass(plan, *p, select) for p in partial]), root)
        calls = 0
        r = plan.resolution
        for k, face, region in partial:
            found = face.recorded
            made = None
            if found is not None and found[0] is face.every and found[0][0] is select:
                col, row = face.tile
                x, y, w, h = region
                made = frame.replay_draws(found[1], root, (col * r + x, plan.target.size[1] - (row * r + y) - h, w, h))
            if made is None:
                description = _every_caster_pass(plan, k, face, region, select)
                made, recorded = frame.run_recorded(_MapPasses([description]), root)
                face.recorded = None if recorded is None else (face.every, recorded)
            else:
                report["replayed"] += 1
            calls += made
        return calls

    def _casters_in(
        self, casters: list[tuple[Any, np.ndarray, np.ndarray]], face: _Face, signature: bytes, resolution: int,
        region: tuple[int, int, int, int],
    ) -> Scope:  # fmt: skip
        """A scope of the casters whose boxes meet ``region`` of ``face`` (rows picked from their batches)."""
        batches = []
        for batch, lo, hi in casters:
            rects = self._rects.get((signature, id(batch)))
            if rects is None or rects.batch is not batch or rects.n != len(lo):
                rects = self._rects[(signature, id(batch))] = _Rects(face, batch, lo, hi)
            picks = np.flatnonzero(rects.meets(resolution, region))
            if not len(picks):
                continue
            found = self._scratch.get(id(batch))
            if found is None or found[0] is not batch:
                if found is not None:
                    found[1].release()
                found = self._scratch[id(batch)] = (batch, Batch(batch.geometry, batch.state))
            part = found[1]
            part.rows = batch.rows[picks]
            # a batch with storage gets spare room in its GPU buffer: the next update's few more rows reuse the
            # buffer and its vertex arrays (the storage itself is never written: rows are not appended here)
            part.storage = part.rows
            items = batch.items
            part.items = list(map(items.__getitem__, picks.tolist())) if len(items) == len(batch.rows) else list(items)
            part.uniform = batch.uniform  # rows of a uniform batch are uniform; others read their own materials
            part.dirty, part.sparse, part.position = (0, len(picks)), None, None
            batches.append(part)
        if len(self._scratch) > 2 * len(casters) + 16:  # batches that are gone: their parts are freed
            alive = {id(batch) for batch, _, _ in casters}
            for key in [key for key in self._scratch if key not in alive]:
                self._scratch.pop(key)[1].release()
        segment = Segment([])
        segment.batches = batches
        scope = Scope()
        scope.parts = [segment]
        return scope


class _Rects:
    """A caster batch's rectangles in a face (:func:`_ndc_rects`), row by row, kept up to date with the caster
    journal so a partial update does not project every caster again.

    ``rect[:, :n]`` holds x0, y0, x1, y1 per row (``flags[:, :n]``: behind,
    wholly behind the light camera; None for an orthographic face), with
    spare columns after them so appended rows are written in place.
    """

    __slots__ = ("face", "batch", "rect", "flags", "n")

    def __init__(self, face: _Face, batch: Any, lo: np.ndarray, hi: np.ndarray) -> None:
        self.face, self.batch = face, batch
        self.n = n = len(lo)
        rect, behind, away = _ndc_rects(face, lo, hi)
        self.rect = np.empty((4, n + n // 8 + 16))
        self.rect[:, :n] = rect
        self.flags = None
        if behind is not None:
            self.flags = np.zeros((2, self.rect.shape[1]), bool)
            self.flags[0, :n], self.flags[1, :n] = behind, away

    def _put(self, where: Any, lo: Any, hi: Any) -> None:
        if len(lo) <= _FEW:  # a few rows (what moved): their floats written in place
            rows = range(where.start, where.stop) if isinstance(where, slice) else np.asarray(where).tolist()
            rect, flags = self.rect, self.flags
            lows = lo if isinstance(lo, list) else lo.tolist()
            highs = hi if isinstance(hi, list) else hi.tolist()
            for i, r in zip(rows, _few_rects(self.face, lows, highs), strict=True):
                rect[0, i], rect[1, i], rect[2, i], rect[3, i] = r[0], r[1], r[2], r[3]
                if flags is not None:
                    flags[0, i], flags[1, i] = r[4], r[5]
            return
        rect, behind, away = _ndc_rects(self.face, lo, hi)
        for j in range(4):
            self.rect[j, where] = rect[j]
        if self.flags is not None:
            self.flags[0, where], self.flags[1, where] = behind, away

    def follow(self, change: Any) -> None:
        """Take one journal entry of the batch: rows moved, a row removed (the last into its place) or appended."""
        if not change.edit:
            if change.new:  # moved rows: their new places
                self._put(change.rows, change.lo, change.hi)
            return
        index = int(change.rows[0])
        last = self.n - 1
        if not change.new:  # removed: the last row takes its place
            self.rect[:, index] = self.rect[:, last]
            if self.flags is not None:
                self.flags[:, index] = self.flags[:, last]
            self.n = last
            return
        if index != self.n:  # not appended after the last row: made again when next needed
            self.n = -1
            return
        if self.n + len(change.lo) > self.rect.shape[1]:  # full: room for as many again
            grown = np.empty((4, 2 * self.rect.shape[1] + len(change.lo)))
            grown[:, : self.n] = self.rect[:, : self.n]
            self.rect = grown
            if self.flags is not None:
                flags = np.zeros((2, grown.shape[1]), bool)
                flags[:, : self.n] = self.flags[:, : self.n]
                self.flags = flags
        self._put(slice(self.n, self.n + len(change.lo)), change.lo, change.hi)
        self.n += len(change.lo)

    def meets(self, resolution: int, region: tuple[int, int, int, int]) -> np.ndarray:
        """Which rows may cover texels of ``region`` (x, y, width, height of the tile)."""
        x, y, w, h = region
        to_ndc = 2.0 / resolution
        n, r = self.n, self.rect
        hit = (r[0, :n] <= (x + w) * to_ndc - 1.0) & (r[2, :n] >= x * to_ndc - 1.0)
        hit &= (r[1, :n] <= (y + h) * to_ndc - 1.0) & (r[3, :n] >= y * to_ndc - 1.0)
        if self.flags is not None:
            hit = (hit | self.flags[0, :n]) & ~self.flags[1, :n]
        return hit


#: a face whose changed region covers more than this fraction of it is redrawn in full (where a partial update
#: stopped paying on llvmpipe: bench/shadow_partial.py)
PARTIAL_MAX = 0.45
#: fitted bounds are snapped outward to a grid of 2**-FIT_GRID of their extent (rounded up to a power of two)
FIT_GRID = 5


def fit_bounds(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The casters' bounds the faces are fitted to: ``[lo, hi]`` snapped outward to a grid of 1/32 to 1/16 of
    its extent, so casters that move inside it keep every face's projection (and the maps drawn)."""
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    extent = float((hi - lo).max())
    if not math.isfinite(extent) or extent <= 0.0:
        return lo, hi
    step = 2.0 ** (math.ceil(math.log2(extent)) - FIT_GRID)
    return np.floor(lo / step) * step, np.ceil(hi / step) * step


def _signature(face: _Face, resolution: int) -> bytes:
    """What a face's texels depend on: its light camera, its tile and the resolution."""
    return face.view.tobytes() + face.proj.tobytes() + bytes(repr((face.tile, resolution)), "ascii")


def _face_pass(plan: ShadowPlan, k: int, face: _Face, select: Any = casts_shadows) -> Pass:
    """The depth pass of face ``k`` drawn in full: its tile cleared and every caster that ``select`` picks
    (None: every opaque item) drawn under a scissor."""
    r = plan.resolution
    col, row = face.tile
    box = (col * r, plan.target.size[1] - (row + 1) * r, r, r)  # the tile, from the atlas's top-left corner
    return Pass(
        f"shadow-map[{k}]",
        items="opaque",
        select=select,
        scopes="items",
        source="scene",
        target=plan.target,
        viewport=(col * r, row * r, r, r),
        clear=Clear(color=None, depth=1.0, box=box),
        state=((ScissorTest, box),),  # a (kind, value) pair: no component is made per frame
        camera=(face.view, face.proj),
        shader=_DEPTH_ONLY,
    )


def _partial_pass(plan: ShadowPlan, k: int, face: _Face, region: tuple[int, int, int, int]) -> Pass:
    """The depth pass that redraws ``region`` (x, y, width, height texels of the tile from its bottom-left corner)
    of face ``k``: cleared and drawn under a scissor; it draws the scope it is run on (the casters that meet the
    region).  Derived from a pattern made once per face (:meth:`Pass.scissored`: no pass is checked per frame)."""
    template = face.template
    if template is None:
        full = _face_pass(plan, k, face, None)
        template = face.template = Pass(
            f"shadow-map[{k}] partial", items="opaque", scopes="items", source="scope", target=plan.target,
            viewport=full.viewport, clear=full.clear, camera=full.camera, shader=_DEPTH_ONLY,
        )  # fmt: skip
    r = plan.resolution
    col, row = face.tile
    x, y, w, h = region
    return template.scissored((col * r + x, plan.target.size[1] - (row * r + y) - h, w, h))


def _every_caster_pass(plan: ShadowPlan, k: int, face: _Face, region: tuple[int, int, int, int], select: Any) -> Pass:
    """The depth pass that redraws ``region`` of face ``k`` drawing every caster ``select`` picks (the full pass
    of the face under the region's scissor and clear box: :attr:`ShadowMapStage.partial_picks` False); derived
    from the face's full pass, made once per face and select."""
    every = face.every
    if every is None or every[0] is not select:
        every = face.every = (select, _face_pass(plan, k, face, select))
    r = plan.resolution
    col, row = face.tile
    x, y, w, h = region
    return every[1].scissored((col * r + x, plan.target.size[1] - (row * r + y) - h, w, h), every[1].name + " partial")


#: GL renderers that rasterise on the CPU (substrings of GL_RENDERER, lower case): every vertex costs CPU time
_SOFTWARE = ("llvmpipe", "softpipe", "swrast", "software")


def software_rasterizer(ctx: Any) -> bool:
    """Whether ``ctx`` renders on the CPU (llvmpipe, softpipe): drawing what a scissor rejects costs time there."""
    renderer = str(ctx.info.get("GL_RENDERER", "")).lower()
    return any(name in renderer for name in _SOFTWARE)


_DEPTH_ONLY = Shader(depth_only=True)


def _changed_boxes(changes: list[Any]) -> tuple[list[list[float]], list[list[float]]] | None:
    """The boxes of the journal's changes, old and new (lists of [x, y, z] corners), less the rows that left and
    came back to the same place in the same batch (a replaced ``Material``).

    One pass of Python floats over the journal's rows (a few per frame: what
    moved; the journal holds at most ``JOURNAL_ROWS``): a left place and a
    taken one cancel when their batch and corners are equal.
    """
    if not changes:
        return [], []
    if len(changes) == 1 or all(c.new for c in changes) or not any(c.new for c in changes):
        return [a for c in changes for a in c.lows()], [b for c in changes for b in c.highs()]
    if len(changes) == 2 and changes[0].batch is changes[1].batch and len(changes[0].lo) == len(changes[1].lo) == 1:
        a, b = changes  # one row left and one came (a replaced Material): the same box cancels
        lows, highs = a.lows() + b.lows(), a.highs() + b.highs()
        if lows[0] == lows[1] and highs[0] == highs[1] and _depth_only_state(a.batch):
            return [], []
        return lows, highs
    left: dict[tuple[int, tuple[float, ...]], list[int]] = {}
    lows: list[list[float]] = []
    highs: list[list[float]] = []
    olds: list[int] = []  # where the left places are in lows/highs
    for c in changes:
        if c.new:
            continue
        for a, b in zip(c.lows(), c.highs(), strict=True):
            left.setdefault((id(c.batch), (*a, *b)), []).append(len(lows))
            olds.append(len(lows))
            lows.append(a)
            highs.append(b)
    cancelled: set[int] = set()
    for c in changes:
        if not c.new:
            continue
        same = _depth_only_state(c.batch)
        for a, b in zip(c.lows(), c.highs(), strict=True):
            found = left.get((id(c.batch), (*a, *b))) if same else None
            if found:
                cancelled.add(found.pop())
            else:
                lows.append(a)
                highs.append(b)
    if cancelled:
        keep = [i for i in range(len(lows)) if i not in cancelled]
        lows, highs = [lows[i] for i in keep], [highs[i] for i in keep]
    return lows, highs


def _depth_only_state(batch: Any) -> bool:
    """Whether a batch's depth depends only on its geometry and placement (no alpha test reading the rows'
    colours): then a row that left and came back to the same place changed nothing in the maps."""
    from ..engine.attributes import AlphaTest

    return batch.state.value(AlphaTest) is None


#: boxes up to this many are projected in Python floats (numpy's per-call cost is more for a few)
_FEW = 8


def _ndc_rects(face: _Face, lo: np.ndarray, hi: np.ndarray) -> tuple[list[np.ndarray], Any, Any]:
    """The rectangles [x0, y0, x1, y1] (four arrays, the face's normalised coordinates) that the boxes [lo, hi]
    may cover in ``face``, with which reach behind its light camera (then they may cover all of it) and which
    lie wholly behind it (none of it); both None for an orthographic face."""
    if len(lo) <= _FEW:
        rects = _few_rects(face, lo.tolist(), hi.tolist())
        columns = [np.array([r[j] for r in rects], np.float64) for j in range(4)]
        if face.ortho:
            return columns, None, None
        return columns, np.array([r[4] for r in rects], bool), np.array([r[5] for r in rects], bool)
    m = face.matrix
    if face.ortho:  # orthographic: centre and half extent
        # column by column, in arrays of N: numpy's (N, 3) @ (3, 2) products and axis-0 reductions are many
        # times slower, and (N, 4) arrays are big enough for allocations that map fresh pages
        total = [lo[:, k] + hi[:, k] for k in range(3)]
        size = [hi[:, k] - lo[:, k] for k in range(3)]
        rect: list[np.ndarray] = [np.empty(0)] * 4
        for j in range(2):
            a = m[j, :3] / (2.0 * m[3, 3])
            c = total[0] * a[0] + total[1] * a[1] + total[2] * a[2] + m[j, 3] / m[3, 3]
            e = size[0] * abs(a[0]) + size[1] * abs(a[1]) + size[2] * abs(a[2])
            rect[j], rect[j + 2] = c - e, c + e
        return rect, None, None
    pick = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], bool)
    corners = np.where(pick[None, :, :], hi[:, None, :], lo[:, None, :])  # (N, 8, 3)
    w = corners @ m[3, :3] + m[3, 3]
    ahead = w > 1e-9
    w = np.where(ahead, w, 1.0)
    x = (corners @ m[0, :3] + m[0, 3]) / w
    y = (corners @ m[1, :3] + m[1, 3]) / w
    return [x.min(axis=1), y.min(axis=1), x.max(axis=1), y.max(axis=1)], ~ahead.all(axis=1), ~ahead.any(axis=1)


def _few_rects(
    face: _Face, lows: list[list[float]], highs: list[list[float]]
) -> list[tuple[float, float, float, float, bool, bool]]:
    """:func:`_ndc_rects` of a few boxes in Python floats: per box x0, y0, x1, y1, whether it reaches behind the
    light camera (its rectangle is then all of the face) and whether it lies wholly behind it."""
    m = face.rows
    out = []
    if face.ortho:  # centre and half extent: an affine map
        s = 1.0 / m[3][3]
        (a0, a1, a2, a3), (b0, b1, b2, b3) = ([v * s for v in m[0]], [v * s for v in m[1]])
        for lo, hi in zip(lows, highs, strict=True):
            cx, cy, cz = (lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5, (lo[2] + hi[2]) * 0.5
            ex, ey, ez = (hi[0] - lo[0]) * 0.5, (hi[1] - lo[1]) * 0.5, (hi[2] - lo[2]) * 0.5
            x = a0 * cx + a1 * cy + a2 * cz + a3
            y = b0 * cx + b1 * cy + b2 * cz + b3
            dx = abs(a0) * ex + abs(a1) * ey + abs(a2) * ez
            dy = abs(b0) * ex + abs(b1) * ey + abs(b2) * ez
            out.append((x - dx, y - dy, x + dx, y + dy, False, False))
        return out
    for lo, hi in zip(lows, highs, strict=True):
        xs, ys, ahead = [], [], 0
        for x in (lo[0], hi[0]):
            for y in (lo[1], hi[1]):
                for z in (lo[2], hi[2]):
                    w = m[3][0] * x + m[3][1] * y + m[3][2] * z + m[3][3]
                    if w <= 1e-9:
                        continue
                    ahead += 1
                    xs.append((m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3]) / w)
                    ys.append((m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3]) / w)
        if ahead == 8:
            out.append((min(xs), min(ys), max(xs), max(ys), False, False))
        else:  # behind the light camera in part (all of the face) or wholly (none of it)
            out.append((-1.0, -1.0, 1.0, 1.0, True, ahead == 0))
    return out


def _face_region(
    face: _Face, resolution: int, lo: np.ndarray | list[list[float]], hi: np.ndarray | list[list[float]]
) -> tuple[int, int, int, int] | None:
    """The texel rectangle (x, y, width, height from the tile's bottom-left corner, one texel of margin) the boxes
    [lo, hi] ((N, 3) arrays or lists of corners) may cover in ``face``; None when they cover none of it."""
    if len(lo) <= 4 * _FEW:  # a few boxes (what moved in a frame): plain floats, not dozens of tiny numpy calls
        lows = lo.tolist() if isinstance(lo, np.ndarray) else lo
        highs = hi.tolist() if isinstance(hi, np.ndarray) else hi
        return _few_region(_few_rects(face, lows, highs), resolution)
    (x0, y0, x1, y1), behind, away = _ndc_rects(face, np.asarray(lo, np.float64), np.asarray(hi, np.float64))
    if behind is not None:
        x0, y0, x1, y1 = (np.where(behind, edge, v) for v, edge in zip((x0, y0, x1, y1), (-1, -1, 1, 1), strict=True))
    half = resolution / 2.0
    x0 = np.clip(np.floor((x0 + 1.0) * half) - 1, 0, resolution)
    y0 = np.clip(np.floor((y0 + 1.0) * half) - 1, 0, resolution)
    x1 = np.clip(np.ceil((x1 + 1.0) * half) + 1, 0, resolution)
    y1 = np.clip(np.ceil((y1 + 1.0) * half) + 1, 0, resolution)
    inside = (x1 > x0) & (y1 > y0)
    if away is not None:
        inside &= ~away
    if not inside.any():
        return None
    left, bottom = int(x0[inside].min()), int(y0[inside].min())
    return left, bottom, int(x1[inside].max()) - left, int(y1[inside].max()) - bottom


def _few_region(
    rects: list[tuple[float, float, float, float, bool, bool]], resolution: int
) -> tuple[int, int, int, int] | None:
    """:func:`_face_region` of a few boxes' rectangles (:func:`_few_rects`)."""
    half = resolution / 2.0
    box: list[float] | None = None
    for x0, y0, x1, y1, _, away in rects:
        if away:
            continue  # wholly behind the light camera
        x0 = min(max(math.floor((x0 + 1.0) * half) - 1, 0), resolution)
        y0 = min(max(math.floor((y0 + 1.0) * half) - 1, 0), resolution)
        x1 = min(max(math.ceil((x1 + 1.0) * half) + 1, 0), resolution)
        y1 = min(max(math.ceil((y1 + 1.0) * half) + 1, 0), resolution)
        if x1 <= x0 or y1 <= y0:
            continue
        box = [x0, y0, x1, y1] if box is None else [min(box[0], x0), min(box[1], y0), max(box[2], x1), max(box[3], y1)]
    if box is None:
        return None
    return int(box[0]), int(box[1]), int(box[2] - box[0]), int(box[3] - box[1])


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def _up_for(axis: np.ndarray) -> np.ndarray:
    return np.array([0.0, 1.0, 0.0]) if abs(axis[1]) < 0.95 else np.array([1.0, 0.0, 0.0])


def _light_faces(light: Any, matrix: np.ndarray, lo: np.ndarray, hi: np.ndarray, resolution: int) -> list[_Face]:
    """The map faces of one light over the casters' bounds [lo, hi] (empty: the light casts no shadows)."""
    from ...attributes import AreaLight, DirectionalLight, PointLight, SpotLight

    if not getattr(light, "casts_shadows", False):
        return []
    corners = _corners(lo, hi)
    center = (lo + hi) / 2.0
    radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-6)
    if isinstance(light, DirectionalLight):
        d = light.world_direction(matrix)
        view = look_at_matrix(center - d * 2.0 * radius, center, _up_for(d))
        eye = corners @ view[:3, :3].T + view[:3, 3]
        half_x = max(float(np.abs(eye[:, 0]).max()), 1e-6) * 1.02
        half_y = max(float(np.abs(eye[:, 1]).max()), 1e-6) * 1.02
        depth = -eye[:, 2]
        near, far = float(depth.min()) - 0.01 * radius, float(depth.max()) + 0.01 * radius
        proj = orthographic_matrix(2.0 * half_y, half_x / half_y, near, far)
        return [_Face(view, proj, (2.0 * max(half_x, half_y) / resolution, 0.0))]
    if not isinstance(light, (PointLight, SpotLight, AreaLight)):
        return []
    p = light.world_position(matrix)  # an area light's centre: its soft shadows filter these maps (area_glsl)
    rel = corners - p
    far = float(np.linalg.norm(rel, axis=1).max()) * 1.01
    gap = np.maximum(np.maximum(lo - p, p - hi), 0.0)
    near = max(float(np.linalg.norm(gap)) * 0.95, far * 2e-3)
    if near >= far:
        near = far * 0.5
    if isinstance(light, SpotLight) and light.cutoff <= _MAX_SPOT_CUTOFF:
        axis = light.world_direction(matrix)
        fov = min(2.0 * light.cutoff + 2.0, 179.0)
        view = look_at_matrix(p, p + axis, _up_for(axis))
        face = _cropped_face(view, math.tan(math.radians(fov) / 2.0), near, far, lo, hi, resolution)
        return [face] if face is not None else []
    rlo, rhi = lo - p, hi - p
    faces = []
    for axis, up in _CUBE:
        a = np.asarray(axis, np.float64)
        view = look_at_matrix(p, p + a, up)
        face = _cropped_face(view, 1.0, near, far, lo, hi, resolution) if _sees(a, rlo, rhi) else None
        if face is None:  # the face sees no caster: a placeholder, not drawn (looked up as lit)
            face = _Face(view, perspective_matrix(90.0, 1.0, near, far), (0.0, 2.0 / resolution), False)
        faces.append(face)
    return faces


def _cropped_face(
    view: np.ndarray, k: float, near: float, far: float, lo: np.ndarray, hi: np.ndarray, resolution: int
) -> _Face | None:
    """A perspective face (half-width ``k`` at distance 1) cropped to the casters' rectangle in it; None: none."""
    crop = frustum_crop(view, k, near, lo, hi)
    if crop is None:
        return None
    x0, y0, x1, y1 = crop
    mx, my = (x1 - x0) * _CROP_MARGIN + 1e-4, (y1 - y0) * _CROP_MARGIN + 1e-4
    x0, y0, x1, y1 = max(x0 - mx, -1.0), max(y0 - my, -1.0), min(x1 + mx, 1.0), min(y1 + my, 1.0)
    sx, sy = (x1 - x0) / 2.0, (y1 - y0) / 2.0
    # the crop rectangle becomes the whole of NDC: x' = (x - cx) / sx
    crop_matrix = np.array(
        [[1 / sx, 0, 0, -(x0 + x1) / 2 / sx], [0, 1 / sy, 0, -(y0 + y1) / 2 / sy], [0, 0, 1, 0], [0, 0, 0, 1]]
    )
    proj = crop_matrix @ perspective_matrix(math.degrees(2.0 * math.atan(k)), 1.0, near, far)
    return _Face(view, proj, (0.0, 2.0 * k * max(sx, sy) / resolution))


_BOX_FACES = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3))


def _clip_polygon(poly: list[np.ndarray], w: np.ndarray, c: float) -> list[np.ndarray]:
    """Sutherland-Hodgman: the part of a convex polygon where ``w . p + c >= 0``."""
    out = []
    for i in range(len(poly)):
        p, q = poly[i], poly[(i + 1) % len(poly)]
        fp, fq = float(w @ p + c), float(w @ q + c)
        if fp >= 0.0:
            out.append(p)
        if (fp >= 0.0) != (fq >= 0.0):
            out.append(p + (q - p) * (fp / (fp - fq)))
    return out


def frustum_crop(
    view: np.ndarray, k: float, near: float, lo: np.ndarray, hi: np.ndarray
) -> tuple[float, float, float, float] | None:
    """The rectangle (x0, y0, x1, y1) in [-1, 1]^2 (units of ``k``) that the box [lo, hi] covers inside the square
    frustum ``|x|, |y| <= k d``, ``d = -z >= near`` of the camera ``view``; None when no part of it is inside.

    The box's faces are clipped by the frustum's planes and the clipped
    polygons projected: the exact bounding rectangle of what a face can see.
    """
    eye = _corners(lo, hi) @ view[:3, :3].T + view[:3, 3]
    planes = [(np.array([sx, sy, -k]), 0.0) for sx, sy in ((-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0))]
    planes.append((np.array([0.0, 0.0, -1.0]), -near))
    points = []
    for face in _BOX_FACES:
        poly = [eye[i] for i in face]
        for w, c in planes:
            poly = _clip_polygon(poly, w, c)
            if not poly:
                break
        points.extend(poly)
    if not points:
        return None
    pts = np.array(points)
    d = np.maximum(-pts[:, 2], 1e-12) * k
    x, y = pts[:, 0] / d, pts[:, 1] / d
    x0, y0, x1, y1 = (float(np.clip(v, -1.0, 1.0)) for v in (x.min(), y.min(), x.max(), y.max()))
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1, y1


def _sees(axis: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the cube face along ``axis`` may see part of the box [lo, hi] (relative to the light).

    Conservative: the face sees the points whose coordinate along its axis is
    positive and at least the other two coordinates' magnitudes.
    """
    k = int(np.argmax(np.abs(axis)))
    sign = axis[k]
    reach = hi[k] if sign > 0 else -lo[k]
    if reach <= 0.0:
        return False
    for j in range(3):
        if j != k:
            nearest = 0.0 if lo[j] <= 0.0 <= hi[j] else min(abs(lo[j]), abs(hi[j]))
            if nearest > reach:
                return False
    return True
