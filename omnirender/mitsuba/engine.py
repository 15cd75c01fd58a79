"""The Mitsuba engine: evaluates a scene graph into a Mitsuba 3 scene.

Painters (service ``"mitsuba.paint"``, see :mod:`.painters`) turn shapes into
Mitsuba shape plugins with ``to_world`` matrices or into in-memory meshes;
attribute painters collect lights, emitters, the integrator and the
background.  The BSDF of a shape is converted from the active appearance
attributes (:meth:`MitsubaEngine.current_bsdf`), cached per combination so
shapes with the same look share one Mitsuba object.  After a traversal
:meth:`MitsubaEngine.scene_dict` assembles sensor, film, integrator, emitters
and shapes, and :meth:`MitsubaEngine.load` instantiates it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..attributes import Material, Mirror, PBRMaterial, Texture
from ..attributes.clipping import ClipRecords
from ..attributes.surface import resolve_surface
from ..core import Camera, Engine, Technique
from . import convert
from ._mi import mitsuba, transform
from .attributes import BSDF, Emitter

__all__ = ["MitsubaEngine", "DEFAULT_INTEGRATOR"]

#: The integrator used when the scene has no ``om.mitsuba.Integrator``.  Directly
#: visible emitters (the ambient environment) are hidden so that the background
#: stays black and colours are premultiplied by coverage, unless the scene has
#: area emitters (emissive materials), which must stay visible.
DEFAULT_INTEGRATOR: dict[str, Any] = {"type": "path", "max_depth": 8, "hide_emitters": True}

#: A cheap pass for the pixel coverage (alpha) and depth: first hits only
#: (Mitsuba's ``depth`` integrator writes the ray distance to R, G, B and the hit to A).
COVERAGE_INTEGRATOR: dict[str, Any] = {"type": "depth"}
#: The coverage pass for scenes with ``mask`` BSDFs (opacity, texture alpha), which the
#: ``depth`` integrator does not see through: a short path tracer's alpha, depth as an AOV
#: (channels R, G, B, A, depth).
MASKED_COVERAGE_INTEGRATOR: dict[str, Any] = {
    "type": "aov",
    "aovs": "dd.y:depth",
    "hits": {"type": "path", "max_depth": 2, "hide_emitters": True},
}

_WRAP = {"repeat": "repeat", "clamp": "clamp", "mirror": "mirror"}
_FILTER = {"linear": "bilinear", "nearest": "nearest"}


class MitsubaEngine(Engine):
    """Builds a Mitsuba scene dict from a scene graph (service ``"mitsuba.paint"``).

    ``size`` is the film size (width, height).  Use :func:`omnirender.mitsuba.render`
    for the whole job; the engine is for users who want the Mitsuba scene
    itself (``engine.run(scene); mi_scene = engine.load()``).
    """

    service = "mitsuba.paint"
    uses_camera_mask = True

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        *,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: str | Callable[[frozenset[str]], bool] | None = None,
    ) -> None:
        super().__init__(technique=technique, on_missing=on_missing, mask=mask)
        w, h = (int(v) for v in size)
        if w <= 0 or h <= 0:
            raise ValueError(f"MitsubaEngine: size must be positive, got {size!r}")
        self.size = (w, h)
        #: GL's global ambient light added to the lights' ambient terms (0 turns it off)
        self.global_ambient = convert.GLOBAL_AMBIENT
        #: give scenes without lights the GL engine's headlight
        self.headlight = True
        self.clear()

    # -- collected scene ----------------------------------------------------
    def clear(self) -> None:
        """Forget everything collected by earlier traversals."""
        #: shape plugins (dicts or Mitsuba objects) by unique key, in evaluation order
        self.shapes: dict[str, Any] = {}
        #: emitter plugin dicts by unique key
        self.emitters: dict[str, Any] = {}
        #: (light, world matrix) pairs still to convert (converted in scene_dict)
        self.pending_lights: list[tuple[Any, np.ndarray]] = []
        #: the integrator plugin dict from an ``om.mitsuba.Integrator``, or None
        self.integrator: dict[str, Any] | None = None
        #: the RGBA colour of the active ``om.Background`` at the root, or None
        self.background: tuple[float, ...] | None = None
        self._bsdfs: dict[tuple, Any] = {}
        self._emitter_ids: set[int] = set()
        #: Color / Material / PBRMaterial in the order they became active (see :meth:`surface`)
        self.surface_stack: list[Any] = []
        #: whether some shape got an area emitter (then emitters cannot be hidden)
        self.has_area_emitters = False
        #: whether some BSDF is a ``mask`` (see-through parts change the coverage)
        self.has_masks = False
        self._count = 0
        self._lights_converted = False
        #: active clip planes with their world rows, see :meth:`clip_planes`
        self._clips = ClipRecords()

    # -- clip planes ----------------------------------------------------------
    def add_clip(self, plane: Any) -> None:
        """Record an added ``ClipPlane`` in world coordinates (the model matrix at this moment)."""
        self._clips.add(plane, self.model_matrix())

    def remove_clip(self, plane: Any) -> None:
        """Forget the most recent record of ``plane`` (it was removed or its node ended)."""
        self._clips.remove(plane)

    def clip_planes(self) -> list[np.ndarray]:
        """World plane rows ``(a, b, c, d)`` (kept: ``a x + b y + c z + d >= 0``) of the active clip planes.

        Mitsuba has no clip planes: painters clip the geometry itself
        (:mod:`omnirender.geometry.clip`), native quadrics fall back to meshes.
        """
        return self._clips.rows()

    def unique_name(self, kind: str) -> str:
        """A fresh key for the scene dict (``"003_sphere"``)."""
        self._count += 1
        return f"{self._count:05d}_{kind}"

    def add_emitter(self, plugin: dict[str, Any], kind: str = "emitter") -> str:
        """Add a scene-level emitter plugin dict; returns its key."""
        key = self.unique_name(kind)
        self.emitters[key] = plugin
        return key

    def add_light(self, light: Any) -> None:
        """Queue a generic light (with its world matrix from ``lights()``) for conversion."""
        matrix = np.eye(4)
        for other, m in self.lights():
            if other is light:
                matrix = m
                break
        else:
            matrix = self.model_matrix()
        self.pending_lights.append((light, np.array(matrix)))

    def add_shape(self, plugin: Any, kind: str, *, two_sided: bool = True) -> str:
        """Add a shape plugin dict (its BSDF and area emitter filled from the state); returns its key."""
        if isinstance(plugin, dict):
            plugin.setdefault("bsdf", self.current_bsdf(two_sided=two_sided))
            emitter = self.current_area_emitter()
            if emitter is not None:
                plugin.setdefault("emitter", emitter)
        key = self.unique_name(kind)
        self.shapes[key] = plugin
        return key

    def surface(self) -> tuple[Any, Any]:
        """(material, colour) as the GL engine resolves them (see :func:`resolve_surface`): a
        Color active after the material replaces its diffuse/base colour and scales its opacity."""
        return resolve_surface(self.surface_stack)

    def current_bsdf(self, *, two_sided: bool = True, vertex_colors: bool = False, texcoords: bool = True) -> Any:
        """The Mitsuba BSDF object for the active appearance attributes (cached).

        Priority: ``om.mitsuba.BSDF`` (passed through), ``PBRMaterial``,
        ``Material``, ``Color``, default grey.  A ``Texture`` (when the shape
        has texture coordinates) or per-vertex colours replace the diffuse
        colour.  Converted BSDFs are two-sided and use ``mask`` for opacity < 1.
        """
        user = self.mono(BSDF)
        tex = self.mono(Texture) if texcoords else None
        material, color = self.surface()
        mirror = self.mono(Mirror)
        key = tuple((id(a), a.version) if a is not None else None for a in (user, tex, material, color, mirror)) + (
            two_sided,
            vertex_colors,
        )
        found = self._bsdfs.get(key)
        if found is None:
            plugin = self._bsdf_dict(user, tex, material, color, two_sided, vertex_colors)
            found = self._bsdfs[key] = self.instantiate(plugin, "om.mitsuba.BSDF" if user is not None else "BSDF")
        return found

    def instantiate(self, plugin: dict[str, Any], what: str) -> Any:
        """``mi.load_dict(plugin)``; Mitsuba's refusal becomes a ValueError naming ``what`` and the node."""
        try:
            return mitsuba().load_dict(plugin)
        except RuntimeError as exc:
            where = self.node_path or "/"
            raise ValueError(
                f"{what} {plugin.get('type')!r} in node {where}: Mitsuba rejected the plugin dict: {exc}; "
                f"check the plugin name and parameters against Mitsuba's plugin reference"
            ) from None

    def _bsdf_dict(self, user, tex, material, color, two_sided, vertex_colors) -> dict[str, Any]:
        if user is not None:
            plugin = user.plugin_dict()
            self.has_masks |= plugin.get("type") == "mask"
            return plugin
        reflectance = None
        if tex is not None:
            self.texture_image(tex)  # a missing image file fails here, naming the node
            reflectance = self._texture_dict(tex)
        elif vertex_colors:
            reflectance = {"type": "mesh_attribute", "name": "vertex_color"}
        elif color is not None and material is not None:
            reflectance = convert.rgb(color.rgb)
        if isinstance(material, PBRMaterial):
            bsdf, opacity = convert.pbr_bsdf(material, reflectance), material.opacity
        elif isinstance(material, Material):
            bsdf, opacity = convert.material_bsdf(material, reflectance), material.opacity
        else:
            bsdf, opacity = convert.color_bsdf(color, reflectance), 1.0
        mirror = self.mono(Mirror)
        if mirror is not None and mirror.reflectance > 0.0:
            # the surface with weight 1 - reflectance, a perfect mirror with weight reflectance (as GL blends them)
            mirror_bsdf = {"type": "conductor", "material": "none"}
            bsdf = {"type": "blendbsdf", "weight": float(mirror.reflectance), "bsdf_0": bsdf, "bsdf_1": mirror_bsdf}
        if color is not None:
            opacity *= color.a
        bsdf = convert.wrap_bsdf(bsdf, float(opacity), two_sided)
        if tex is not None and tex.image_array()[:, :, 3].min() < 255:
            # the texture's alpha cuts the surface out (GL multiplies it into the alpha)
            alpha = np.ascontiguousarray(tex.image_array()[::-1, :, 3:4].astype(np.float32) / 255.0)
            cutout = {"type": "bitmap", "bitmap": mitsuba().Bitmap(alpha), "raw": True}
            cutout["wrap_mode"] = _WRAP.get(tex.wrap, "repeat")
            bsdf = {"type": "mask", "opacity": cutout, "material": bsdf}
        self.has_masks |= bsdf["type"] == "mask"
        return bsdf

    def texture_image(self, tex: Texture) -> np.ndarray:
        """``tex.image_array()``; a missing or unreadable image file raises naming the node and the fix."""
        return tex.image_in("MitsubaEngine", self.node_path)

    def _texture_dict(self, tex: Texture) -> dict[str, Any]:
        mi = mitsuba()
        rgba = tex.image_array()
        # Mitsuba looks up v = 0 in the image's first row; omnirender follows
        # OpenGL (v = 0 at the bottom row), so the rows are flipped.
        image = np.ascontiguousarray(rgba[::-1, :, :3])
        return {
            "type": "bitmap",
            "bitmap": mi.Bitmap(image),
            "wrap_mode": _WRAP.get(tex.wrap, "repeat"),
            "filter_type": _FILTER.get(tex.filter, "bilinear"),
        }

    def current_area_emitter(self) -> Any:
        """An area emitter object for the next shape (emissive material or ``om.mitsuba.Emitter("area")``)."""
        mi = mitsuba()
        areas = [e for e in self.poly(Emitter) if e.is_area]
        if areas:
            self.has_area_emitters = True
            return self.instantiate(areas[-1].plugin_dict(), "om.mitsuba.Emitter")
        material, _ = self.surface()
        if material is not None and max(material.emission) > 0.0:
            self.has_area_emitters = True
            return mi.load_dict({"type": "area", "radiance": convert.rgb(material.emission)})
        return None

    # -- evaluation ---------------------------------------------------------
    def begin(self, root: Any) -> None:
        self.clear()
        super().begin(root)

    def reference_point(self) -> np.ndarray:
        """Where GL-style light attenuation is matched: the camera's centre of interest."""
        camera, world = self.camera_or_default()
        return (np.asarray(world, np.float64) @ np.array([*camera.center, 1.0]))[:3]

    def camera_or_default(self) -> tuple[Camera, np.ndarray]:
        """The pre-evaluated camera, or ``om.Camera()`` (eye at (0, 0, 5)) when the scene has none."""
        if self.camera is not None:
            return self.camera
        return Camera(), np.eye(4)

    # -- assembling ---------------------------------------------------------
    def film_dict(self, rfilter: str = "box") -> dict[str, Any]:
        w, h = self.size
        return {
            "type": "hdrfilm",
            "width": w,
            "height": h,
            "pixel_format": "rgba",
            "component_format": "float32",
            "rfilter": {"type": rfilter},
        }

    def coverage_integrator(self) -> dict[str, Any]:
        """The integrator of the coverage/depth pass; its output has alpha in channel 3 and depth last."""
        return dict(MASKED_COVERAGE_INTEGRATOR if self.has_masks else COVERAGE_INTEGRATOR)

    def integrator_dict(self, integrator: dict[str, Any] | None = None) -> dict[str, Any]:
        """The integrator to use: ``integrator``, else the scene's, else :data:`DEFAULT_INTEGRATOR`."""
        if integrator is not None:
            return dict(integrator)
        if self.integrator is not None:
            return dict(self.integrator)
        return {**DEFAULT_INTEGRATOR, "hide_emitters": not self.has_area_emitters}

    def scene_dict(self, *, integrator: dict[str, Any] | None = None, rfilter: str = "box") -> dict[str, Any]:
        """The Mitsuba scene dict of the last traversal (``integrator`` overrides the scene's)."""
        camera, world = self.camera_or_default()
        sensor = convert.sensor_dict(camera, world, self.size, self.film_dict(rfilter))
        sensor["to_world"] = transform(sensor["to_world"])
        chosen = self.integrator_dict(integrator)
        out: dict[str, Any] = {"type": "scene", "integrator": chosen, "sensor": sensor}
        self.convert_lights()
        out.update(self.emitters)
        out.update(self.shapes)
        return out

    def has_environment(self) -> bool:
        """Whether an environment emitter (seen behind the shapes) is in the scene."""
        return any(isinstance(p, dict) and p.get("type") in convert.ENVIRONMENTS for p in self.emitters.values())

    def convert_lights(self) -> None:
        """Turn the queued generic lights into emitter plugins, as the GL engine lights the scene.

        Point and spot lights are matched at :meth:`reference_point`; ambient terms
        (plus the global ambient) become one constant environment; a scene without
        any light or emitter gets the GL engine's headlight.
        """
        if self._lights_converted:
            return
        self._lights_converted = True
        if not self.pending_lights and not self.emitters and self.headlight:
            self.add_emitter(convert.headlight_emitter(*self.camera_or_default()), "headlight")
        reference = self.reference_point()
        ambient = convert.ambient_emitter(self.pending_lights, self.global_ambient)
        if ambient is not None and not self.has_environment():  # Mitsuba allows one environment
            self.add_emitter(ambient, "ambient")
        for light, matrix in self.pending_lights:
            plugin = convert.light_emitter(light, matrix, reference)
            if plugin is not None:
                if "to_world" in plugin:
                    plugin["to_world"] = transform(plugin["to_world"])
                self.add_emitter(plugin, type(light).__name__.lower())
        self.pending_lights.clear()

    def load(self, **options: Any) -> Any:
        """Instantiate the scene of the last traversal as an ``mi.Scene`` (options: see :meth:`scene_dict`)."""
        d = self.scene_dict(**options)
        try:
            return mitsuba().load_dict(d)
        except RuntimeError as exc:
            raise ValueError(
                f"MitsubaEngine: Mitsuba could not build the scene (integrator {d['integrator'].get('type')!r}, "
                f"{len(self.emitters)} emitters, {len(self.shapes)} shapes): {exc}; check om.mitsuba.Integrator "
                f"and om.mitsuba.Emitter plugin dicts"
            ) from None
