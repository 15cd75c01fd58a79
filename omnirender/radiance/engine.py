"""``RadianceEngine``: evaluates a scene graph into a Radiance scene description.

The engine is the generic state machine with service ``"rad.paint"``.  Shape
painters (:mod:`.painters`) write Radiance surfaces in world coordinates with
:meth:`RadianceEngine.surface` (the modifier comes from the active appearance,
:mod:`.appearance`) or queue triangle meshes for ``obj2mesh``
(:meth:`RadianceEngine.add_mesh`); attribute painters record lights, the
background, fog, clip planes, options and ``Raw`` text.  After a traversal
:meth:`RadianceEngine.description` assembles the ``.rad`` text, with the lights
converted to Radiance sources (:mod:`.lights`) and a header comment holding the
``rpict`` view.  Identifiers are generated (``om_<kind><n>``); each is mapped
to the node that wrote it, so Radiance's error messages can name the node.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..attributes import photometry
from ..attributes.clipping import ClipRecords
from ..attributes.conversion import native_to
from ..attributes.surface import resolve_surface
from ..core import Camera, Engine, Technique
from ..options import check_real
from . import rad
from .attributes import Material as RadMaterial
from .attributes import Options

__all__ = ["RadianceEngine", "MeshJob", "view_arguments"]


@dataclass
class MeshJob:
    """A triangle mesh for ``obj2mesh``: OBJ text, optional Radiance materials (``-a``), output file name."""

    name: str
    obj: str
    materials: str | None = None
    node: str = ""


def _exact(values: Any) -> list[str]:
    out = []
    for v in values:
        rad.number(v, "Radiance camera")  # finite check
        out.append("0" if float(v) == 0.0 else f"{float(v):.17g}")
    return out


def view_arguments(camera: Camera, view: np.ndarray, size: tuple[int, int]) -> list[str]:
    """``rpict`` view options with exactly the projection of ``camera.projection_matrix(w / h)``.

    Perspective (``-vtv``): the vertical angle is the camera's fov and the
    horizontal one spans ``aspect`` times the image plane.  Orthographic
    (``-vtl``): the view is ``height`` tall and ``height * aspect`` wide.  The
    near and far planes become Radiance's fore and aft clipping planes; an
    off-axis camera's ``shift`` becomes the view shift and lift (``-vs``, ``-vl``).
    """
    w, h = size
    aspect = w / h
    eye_to_world = np.linalg.inv(view)
    axes = eye_to_world[:3, :3]
    up = axes[:, 1] / np.linalg.norm(axes[:, 1])
    forward = -axes[:, 2] / np.linalg.norm(axes[:, 2])
    if camera.is_orthographic:
        kind, horizontal, vertical = "-vtl", camera.height * aspect, camera.height
    else:
        half = math.tan(math.radians(camera.fov) / 2.0)
        kind, vertical = "-vtv", camera.fov
        horizontal = math.degrees(2.0 * math.atan(half * aspect))
    return [
        kind,
        "-vp", *_exact(eye_to_world[:3, 3]),
        "-vd", *_exact(forward),
        "-vu", *_exact(up),
        "-vh", *_exact([horizontal]),
        "-vv", *_exact([vertical]),
        "-vo", *_exact([camera.near]),
        "-va", *_exact([camera.far]),
        # off-axis window (camera.shift in image heights): Radiance's view shift and lift, in image widths/heights
        "-vs", *_exact([camera.shift[0] / aspect]),
        "-vl", *_exact([camera.shift[1]]),
    ]  # fmt: skip


class RadianceEngine(Engine):
    """Writes a Radiance scene description for everything evaluated between ``begin`` and ``end``.

    ``size`` (width, height) fixes the view's aspect; ``resource_prefix``
    starts the names of the mesh and picture files the description refers to
    (:attr:`meshes`, :attr:`pictures`; the caller writes them next to it).
    ``global_ambient`` (GL's 0.2) is added to the lights' ambient terms and
    ``headlight`` gives scenes without lights the GL engine's headlight; the
    analysis functions turn both off to compute physical values.

    ``coverage=True`` writes the coverage pass instead: every surface black
    and unlit except for how much it lets through (opacity, texture alpha,
    glass), in front of a white environment seen only by rays passing through
    (a ``glow`` with negative radius), so a picture of it is the fraction of
    each pixel that shows the background.  ``shared`` is the engine of the
    main pass whose mesh and picture files it reuses.
    """

    service = "rad.paint"
    uses_camera_mask = True

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        *,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: str | Callable[[frozenset[str]], bool] | None = None,
        resource_prefix: str = "om_",
        global_ambient: float = photometry.GLOBAL_AMBIENT,
        headlight: bool = True,
        coverage: bool = False,
        shared: RadianceEngine | None = None,
    ) -> None:
        super().__init__(technique=technique, on_missing=on_missing, mask=mask)
        try:
            w, h = (int(v) for v in size)
        except (TypeError, ValueError):
            raise ValueError(f"RadianceEngine: size must be (width, height), got {size!r}") from None
        if w <= 0 or h <= 0:
            raise ValueError(f"RadianceEngine: size must be positive, got {size!r}")
        self.size = (w, h)
        self.resource_prefix = rad.identifier(resource_prefix, "RadianceEngine resource_prefix")
        self.global_ambient = check_real("RadianceEngine", "global_ambient", global_ambient, 0.0, 1e6)
        self.headlight = bool(headlight)
        self.coverage = bool(coverage)
        self._shared_resources = shared._resources if shared is not None else None
        self.clear()

    # -- collected scene ------------------------------------------------
    def clear(self) -> None:
        """Forget everything written so far."""
        #: materials, patterns, surfaces and raw text in evaluation order
        self.body: list[str] = []
        #: triangle meshes to compile with obj2mesh
        self.meshes: list[MeshJob] = []
        #: (file name, (H, W, 3) linear float array) pictures for colorpict/mixpict
        self.pictures: list[tuple[str, np.ndarray]] = []
        #: (light, world matrix) pairs converted in :meth:`description`
        self.pending_lights: list[tuple[Any, np.ndarray]] = []
        self.background: Any = None
        self.fog: Any = None
        self.options: Options | None = None
        #: identifier -> node path that wrote it
        self.owners: dict[str, str] = {}
        #: Color / Material / PBRMaterial in the order they became active
        self.surface_stack: list[Any] = []
        self._declared: dict[Any, str] = {}
        self._sinks: dict[int, list[str]] = {}
        #: whether some surface lets light through (then the picture needs a coverage pass)
        self.transparent = False
        self.warned_light_switch = False
        self._resources: dict[Any, str] = {} if self._shared_resources is None else self._shared_resources
        self._counts: dict[str, int] = {}
        self._clips = ClipRecords()
        self._lights_text: str | None = None

    def begin(self, root: Any) -> None:
        self.clear()
        super().begin(root)

    def owner(self) -> str:
        """``Radiance (node /path)`` for messages."""
        path = self.node_path
        return f"Radiance (node {path})" if path else "Radiance"

    def new_id(self, kind: str) -> str:
        """A fresh identifier ``om_<kind><n>``, remembered as written by the current node."""
        n = self._counts.get(kind, 0)
        self._counts[kind] = n + 1
        ident = f"om_{kind}{n}"
        self.owners[ident] = self.node_path or "/"
        return ident

    def declare(self, key: Any, kind: str, make: Callable[[str], str], sink: list[str] | None = None) -> str:
        """The identifier for ``key``; on first use ``make(ident)`` gives its definition, appended to ``sink``."""
        ident = self._declared.get(key)
        if ident is None:
            ident = self.new_id(kind)
            self._declared[key] = ident
            (self.body if sink is None else sink).append(make(ident))
        return ident

    def resource(self, key: Any, kind: str, suffix: str) -> tuple[str, bool]:
        """(a safe file name for a resource, whether it is new): ``<prefix><kind><n><suffix>``."""
        name = self._resources.get(key)
        if name is not None:
            return name, False
        n = sum(1 for other in self._resources.values() if other.endswith(suffix))
        name = f"{self.resource_prefix}{kind}{n}{suffix}"
        self._resources[key] = name
        return name, True

    def add_picture(self, key: Any, make: Callable[[], np.ndarray]) -> str:
        """The file name of a Radiance picture for ``key``; ``make()`` gives its linear (H, W, 3) data once."""
        name, new = self.resource(("picture", key), "pic", ".hdr")
        if new:
            self.pictures.append((name, np.asarray(make(), dtype=np.float32)))
        return name

    def add_mesh(self, key: Any, make: Callable[[], tuple[str, str | None] | None]) -> str | None:
        """The ``.rtm`` file name for mesh ``key``; ``make()`` gives (OBJ text, material text or None) once.

        None when ``make()`` returns None: nothing left to draw (clipped away).
        """
        if ("empty", key) in self._resources:
            return None
        name = self._resources.get(("mesh", key))
        if name is not None:
            return name
        made = make()
        if made is None:
            self._resources[("empty", key)] = ""
            return None
        name, _ = self.resource(("mesh", key), "mesh", ".rtm")
        self.meshes.append(MeshJob(name, made[0], made[1], self.node_path))
        return name

    def surface(self, kind: str, reals: Any, modifier: str, *, count: int | None = None) -> None:
        """Write one surface primitive (``sphere``, ``polygon`` ...) with a fresh identifier.

        ``reals`` are numbers, or formatted rows (:func:`rad.rows_text`) with ``count`` values.
        """
        ident = self.new_id("o")
        path = self.node_path
        head = rad.comment(path) + "\n" if path else ""
        self.body.append(head + rad.primitive(modifier, kind, ident, (), reals, self.owner(), real_count=count))

    def surfaces(self, kind: str, rows: np.ndarray, modifier: str) -> None:
        """Many surfaces of one kind (one row of reals each, e.g. cylinders), formatted in one pass."""
        rows = np.asarray(rows, dtype=np.float64)
        if len(rows) == 0:
            return
        ident = self.new_id("o")
        if not np.all(np.isfinite(rows)):
            raise rad.RadError(f"{self.owner()}: {kind} arguments contain non-finite values")
        k = rows.shape[1]
        head = f"{rad.identifier(modifier)} {kind} {ident}\n0\n0\n{k}"
        line = head + "".join(" %.9g" for _ in range(k)) + "\n"
        path = self.node_path
        prefix = rad.comment(path) + "\n" if path else ""
        self.body.append(prefix + (line * len(rows)) % tuple(rows.ravel().tolist()))

    def raw(self, text: str) -> None:
        """Trusted text at this place of the description (``om.radiance.Raw``)."""
        node = self.node_path or "/"
        for name in rad.defined_names(text):
            self.owners.setdefault(name, node)
        self.body.append(rad.comment(node) + "\n" + text.rstrip("\n") + "\n")

    def appearance(self) -> tuple[Any, Any]:
        """(material, colour) as the GL engine resolves them (see :func:`resolve_surface`)."""
        return resolve_surface(self.surface_stack)

    # -- clip planes ----------------------------------------------------
    def add_clip(self, plane: Any) -> None:
        """Record an added ``ClipPlane`` in world coordinates (the model matrix at this moment)."""
        self._clips.add(plane, self.model_matrix())

    def remove_clip(self, plane: Any) -> None:
        """Forget the most recent record of ``plane`` (it was removed or its node ended)."""
        self._clips.remove(plane)

    def clip_planes(self) -> list[np.ndarray]:
        """World plane rows ``(a, b, c, d)`` (kept: ``a x + b y + c z + d >= 0``) of the active clip planes."""
        return self._clips.rows()

    # -- camera -----------------------------------------------------------
    def camera_or_default(self) -> tuple[Camera, np.ndarray]:
        """The pre-evaluated camera, or ``om.Camera()`` (eye at (0, 0, 5)) when the scene has none."""
        if self.camera is not None:
            return self.camera
        return Camera(), np.eye(4)

    def world_view(self) -> np.ndarray:
        """The world-to-eye matrix of :meth:`camera_or_default`."""
        camera, world = self.camera_or_default()
        return camera.view_matrix() @ np.linalg.inv(world)

    def view_arguments(self, size: tuple[int, int] | None = None) -> list[str]:
        """``rpict`` view options for the scene's camera (at ``size``, default the engine's)."""
        camera, _ = self.camera_or_default()
        return view_arguments(camera, self.world_view(), size or self.size)

    def reference_point(self) -> np.ndarray:
        """Where GL-style light attenuation is matched: the camera's centre of interest."""
        camera, world = self.camera_or_default()
        return (np.asarray(world, np.float64) @ np.array([*camera.center, 1.0]))[:3]

    # -- the file -----------------------------------------------------------
    def ambient_value(self) -> np.ndarray:
        """Radiance's ``-av``: the global ambient plus every light's ambient term (GL's ambient light)."""
        if self.coverage:
            return np.zeros(3)
        return photometry.ambient_total(self.pending_lights, self.global_ambient)

    def lights_text(self) -> str:
        """The lights as Radiance sources (converted once, after the traversal)."""
        if self._lights_text is None:
            from .lights import lights_text

            self._lights_text = lights_text(self)
        return self._lights_text

    def description(self) -> str:
        """The complete ``.rad`` text for what was evaluated (lights first, then everything in order)."""
        view = " ".join(self.view_arguments())
        ambient = rad.numbers(self.ambient_value())
        head = (
            "# omnirender scene for Radiance\n"
            f"# view: rpict {view} -x {self.size[0]} -y {self.size[1]} -pa 0 -av {ambient}\n"
        )
        return head + self.lights_text() + "".join(self.body)


# Its own renderer-specific attributes stay on their stacks here (other engines convert them to generic ones).
native_to(RadianceEngine, "rad.paint", RadMaterial)
