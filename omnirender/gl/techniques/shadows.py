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

from ...core.camera import look_at_matrix, orthographic_matrix, perspective_matrix
from ..engine.drawlist import Scope, world_bounds
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
    "MAX_ATLAS",
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

    __slots__ = ("view", "proj", "texel", "drawn", "tile")

    def __init__(self, view: np.ndarray, proj: np.ndarray, texel: tuple[float, float], drawn: bool = True) -> None:
        self.view, self.proj, self.texel, self.drawn = view, proj, texel, drawn
        self.tile: tuple[int, int] | None = None  # (column, row) in the atlas


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
        self.cols, self.rows = cols, rows
        self._arrays()

    def __len__(self) -> int:
        return len(self.faces)

    def features(self) -> tuple[tuple[str, Any], ...]:
        """The program features of a receiver in this frame (a ShadowMaps pass may override the filter)."""
        return (("SHADOW_MAPS", len(self.faces)), ("SHADOW_PCF", pcf_mode(self.settings.softness)))

    def technique(self) -> _MapPasses | None:
        """The depth passes, or None when no face needs drawing."""
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
                    select=casts_shadows,
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
            self.matrices[k] = (face.proj @ face.view).T
            self.texels[k] = face.texel
            if face.tile is not None:
                col, row = face.tile
                r = self.resolution
                self.tiles[k] = (col * r, row * r, r, r)
        self.style = np.asarray(self.settings.style(), np.float32)

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
        for name, data in (("u_shadow_mat", self.matrices), ("u_shadow_tile", self.tiles),
                           ("u_shadow_texel", self.texels), ("u_shadow_style", self.style)):  # fmt: skip
            u = program.get(name, None)
            if u is not None:  # the compiler may trim arrays to the elements a variant reads
                u.write(data[: u.array_length].tobytes() if data.ndim > 1 else data.tobytes())
        u = program.get("u_lshadow", None)
        if u is not None:
            u.write(self.light_array(order, u.array_length).tobytes())


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

    The maps are drawn again only when the casters' bounds, the lights, the settings or the frame size
    changed since the last frame that drew them (the camera is free to move).
    """

    name = "shadow maps"

    def __init__(self) -> None:
        self._cache: Any = None  # (key, plan, its technique)
        self._drawn: Any = None  # (key, caster bounds, size) of the maps the atlas holds

    def changed(self) -> None:
        """Nothing to forget: the engine's render index keeps the casters' bounds up to date."""

    def draw(self, frame: Any, root: Scope) -> int:
        engine = frame.engine
        settings = frame_settings(root if engine.root_scope is not None else None, engine.shadows)
        if settings is None:
            return 0
        lights = [(light, m) for light, m in engine.scene_lights if getattr(light, "casts_shadows", False)]
        if not lights:
            return 0
        # the render index keeps the casters' bounds: a new tuple whenever casters moved (compared below)
        casters = engine.index.caster_bounds() if engine.root_scope is not None else (caster_bounds(root),)
        bounds = casters[0]
        if bounds is None:
            return 0
        key = (id(settings), settings.version, bounds[0].tobytes(), bounds[1].tobytes(),
               tuple((id(light), light.version, m.tobytes()) for light, m in lights), tuple(engine.size))  # fmt: skip
        plan = self._cache[1] if self._cache is not None and self._cache[0] == key else None
        if plan is None:
            plan = ShadowPlan(settings, lights, bounds, tuple(engine.size))
            self._cache = (key, plan, plan.technique())
        technique = self._cache[2]
        if technique is None:
            return 0
        frame.state.shadow_plan = plan
        drawn = (key, casters, tuple(engine.size))
        last = self._drawn
        fresh = last is not None and last[0] == key and last[1] is drawn[1] and last[2] == drawn[2]
        if fresh and frame.keep_target(plan.target):
            return 0  # casters and lights unchanged: the maps of the last frame still hold (the camera is free)
        calls = frame.run(technique, root)
        self._drawn = drawn
        return calls


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
