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

from ..attributes import AreaLight, BumpMap, Mirror, MultiTexture, Texture
from ..attributes.clipping import ClipRecords
from ..attributes.conversion import native_to
from ..attributes.photometry import ambient_total, linear_to_srgb, srgb_to_linear
from ..attributes.surface import Appearance, appearance_key, engine_appearance, resolve_surface
from ..attributes.texturing import bake_layers, scaled_image
from ..core import Camera, Engine, Technique, version_key
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
_MISSING = object()
#: Relative sampling weight of the emitters that carry emission and ambient light (the lights have 1).
AMBIENT_SAMPLING_WEIGHT = 0.02


def wrap_of(texture: Any) -> str:
    """A texture's wrap mode ("repeat" without one)."""
    return "repeat" if texture is None else texture.wrap


def _resampled(rgba8: np.ndarray, rows: int, cols: int, srgb: bool) -> np.ndarray:
    """(rows, cols, 3) linear values of an RGBA8 image (nearest resampling to the size)."""
    h, w = rgba8.shape[:2]
    img = rgba8[(np.arange(rows) * h) // rows][:, (np.arange(cols) * w) // cols, :3].astype(np.float64) / 255.0
    return srgb_to_linear(img) if srgb else img


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
        self._ambient: np.ndarray | None = None

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

    def appearance(self, texcoords: bool = True) -> Appearance:
        """The one appearance model's resolution of the active attributes (textures only with ``texcoords``)."""
        return engine_appearance(self, texcoords=texcoords)

    def _appearance_key(self, texcoords: bool) -> tuple:
        mono = self.mono
        if not texcoords:
            return appearance_key(self.surface_stack)
        return appearance_key(self.surface_stack, mono(Texture), mono(MultiTexture), mono(BumpMap))

    def current_bsdf(self, *, two_sided: bool = True, vertex_colors: bool = False, texcoords: bool = True) -> Any:
        """The Mitsuba BSDF object for the active appearance attributes (cached).

        ``om.mitsuba.BSDF`` is passed through; otherwise the resolved appearance
        (:mod:`omnirender.attributes.surface`): ``principled`` for PBR (textured
        base colour, metallic and roughness), ``diffuse`` / ``roughplastic`` for
        Phong, wrapped in ``normalmap`` (normal maps, bump maps), ``twosided``
        and ``mask`` (blended opacity, cut-outs).  Per-vertex colours are read
        from the mesh (``vertex_colors``).
        """
        user = self.mono(BSDF)
        mirror = self.mono(Mirror)
        key = (
            version_key(user),
            self._appearance_key(texcoords),
            version_key(mirror),
            two_sided,
            vertex_colors,
            texcoords,
        )
        found = self._bsdfs.get(key)
        if found is None:
            if user is not None:
                plugin = user.plugin_dict()
                self.has_masks |= plugin.get("type") == "mask"
            else:
                plugin = self._bsdf_dict(self.appearance(texcoords), two_sided, vertex_colors)
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

    def _base_image(self, app: Appearance) -> np.ndarray | None:
        """The base colour texture (with its layers) times the base colour, RGBA8, or None."""
        if app.texture is None and not app.layers:
            return None
        base = None if app.texture is None else self.texture_image(app.texture)
        image = bake_layers(base, app.layers) if app.layers else base
        factor = (*linear_to_srgb(np.asarray(app.base)), 1.0)
        return scaled_image(image, factor)

    def _bsdf_dict(self, app: Appearance, two_sided: bool, vertex_colors: bool) -> dict[str, Any]:
        image = self._base_image(app)
        wrap = app.texture.wrap if app.texture is not None else "repeat"
        if image is not None:
            reflectance = self._bitmap(image[:, :, :3], wrap, app.texture)
        elif vertex_colors:
            reflectance = {"type": "mesh_attribute", "name": "vertex_color"}
        else:
            reflectance = convert.rgb(app.base, linearize=False)
        if app.model == "pbr":
            bsdf = convert.pbr_bsdf(app, reflectance)
            mr = app.metallic_roughness_texture
            if mr is not None:
                rgba = self.texture_image(mr).astype(np.float32) / 255.0
                bsdf["metallic"] = self._bitmap(rgba[:, :, 2:3] * app.metallic, mr.wrap, mr, raw=True)
                rough = np.maximum(rgba[:, :, 1:2] * app.roughness, 0.01)
                bsdf["roughness"] = self._bitmap(rough, mr.wrap, mr, raw=True)
        else:
            bsdf = convert.material_bsdf(app, reflectance)
        normal, scale = app.normal_map()
        if normal is not None:
            bsdf = {"type": "normalmap", "normalmap": self._normal_bitmap(normal, scale), "bsdf": bsdf}
        mirror = self.mono(Mirror)
        if mirror is not None and mirror.reflectance > 0.0:
            # the surface with weight 1 - reflectance, a perfect mirror with weight reflectance (as GL blends them)
            mirror_bsdf = {"type": "conductor", "material": "none"}
            bsdf = {"type": "blendbsdf", "weight": float(mirror.reflectance), "bsdf_0": bsdf, "bsdf_1": mirror_bsdf}
        opacity = app.alpha if app.alpha_mode == "blend" else 1.0
        bsdf = convert.wrap_bsdf(bsdf, float(opacity), two_sided)
        if image is not None and app.alpha_mode != "opaque" and image[:, :, 3].min() < 255:
            # the texture's alpha: see-through where it is below 1 (blend), cut out below the cutoff (mask)
            alpha = image[:, :, 3:4].astype(np.float32) / 255.0
            if app.alpha_mode == "mask":
                alpha = (alpha >= app.alpha_cutoff).astype(np.float32)
            bsdf = {"type": "mask", "opacity": self._bitmap(alpha, wrap, app.texture, raw=True), "material": bsdf}
        self.has_masks |= bsdf["type"] == "mask"
        return bsdf

    def _bitmap(self, pixels: np.ndarray, wrap: str, texture: Any, raw: bool = False) -> dict[str, Any]:
        """A ``bitmap`` texture dict of (H, W, C) pixels (uint8 sRGB, or float ``raw`` data); rows flipped.

        Mitsuba looks up v = 0 in the image's first row; omnirender follows
        OpenGL (v = 0 at the bottom row).  The texture's transform is
        Mitsuba's ``to_uv``.
        """
        data = np.ascontiguousarray(pixels[::-1])
        out: dict[str, Any] = {
            "type": "bitmap",
            "bitmap": mitsuba().Bitmap(data),
            "wrap_mode": _WRAP.get(wrap, "repeat"),
            "filter_type": _FILTER.get(texture.filter if texture is not None else "linear", "bilinear"),
        }
        if raw:
            out["raw"] = True
        if texture is not None and texture.transformed:
            # the rows are flipped above, so Mitsuba's coordinates are omnirender's: the transform applies as is
            out["to_uv"] = mitsuba().ScalarTransform3f(texture.uv_matrix().tolist())
        return out

    def _normal_bitmap(self, texture: Texture, scale: float) -> dict[str, Any]:
        """A tangent-space normal map for Mitsuba's ``normalmap`` (linear data, x and y scaled by ``scale``)."""
        n = self.texture_image(texture)[:, :, :3].astype(np.float32) / 255.0 * 2.0 - 1.0
        if scale != 1.0:
            n[:, :, :2] *= scale
            n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-6)
        return self._bitmap((n + 1.0) * 0.5, texture.wrap, texture, raw=True)

    def texture_image(self, tex: Texture) -> np.ndarray:
        """``tex.image_array()``; a missing or unreadable image file raises naming the node and the fix."""
        return tex.image_in("MitsubaEngine", self.node_path)

    def current_area_emitter(self, texcoords: bool = True, glow: np.ndarray | None = None, share: float = 1.0) -> Any:
        """The area emitter of the next shape: its emission plus GL's ambient term, or ``om.mitsuba.Emitter("area")``.

        The ambient light every engine adds (GL's global ambient plus the
        lights' ambient terms, times the ambient reflectance) is emitted by the
        surface itself, as POV-Ray's ``ambient`` and GL's ambient term are: no
        environment lights the scene, so Phong materials reflect their own
        ambient colour and shadowed parts are as bright as in GL.  The emitter
        is sampled rarely (``sampling_weight``), so the lights keep the samples;
        ``share`` is the fraction of a vertex-coloured mesh this group of faces
        is (its emitters together keep one emitter's weight: many groups
        each with the full weight took the samples from the lights, speckling
        the surface).
        """
        areas = [e for e in self.poly(Emitter) if e.is_area]
        if areas:
            self.has_area_emitters = True
            return self.instantiate(areas[-1].plugin_dict(), "om.mitsuba.Emitter")
        if self.mono(BSDF) is not None:
            return None
        if glow is not None:
            # a vertex-coloured mesh: the mean of its per-vertex ambient and emission (Mitsuba cannot sample
            # a mesh attribute on an emitter)
            value = np.asarray(glow, np.float64).mean(axis=0)
            if not np.any(value > 0.0):
                return None
            self.has_area_emitters = True
            radiance = convert.rgb(value, linearize=False)
            weight = AMBIENT_SAMPLING_WEIGHT * max(float(share), 1e-6)
            return self.instantiate({"type": "area", "radiance": radiance, "sampling_weight": weight}, "area emitter")
        key = ("emitter", self._appearance_key(texcoords))
        plugin = self._bsdfs.get(key, _MISSING)
        if plugin is _MISSING:
            plugin = self._bsdfs[key] = self._emitter_dict(self.appearance(texcoords))
        if plugin is None:
            return None
        self.has_area_emitters = True
        return self.instantiate(dict(plugin), "area emitter")  # an emitter object belongs to one shape

    def _emitter_dict(self, app: Appearance) -> dict[str, Any] | None:
        ambient_light = self.ambient_light()
        emission = np.asarray(app.emission, np.float64)
        image = self._base_image(app)
        follows = app.ambient_follows_base
        ambient = app.ambient_reflectance() * ambient_light
        if app.occlusion_texture is not None or app.emissive_texture is not None or (image is not None):
            # textured: bake emission + ambient into one linear image over UV set 0
            ref = app.emissive_texture or app.texture or app.occlusion_texture
            rows, cols = self.texture_image(ref).shape[:2] if image is None else image.shape[:2]
            glow = np.zeros((rows, cols, 3), np.float64) + emission
            if app.emissive_texture is not None:
                glow = emission * _resampled(self.texture_image(app.emissive_texture), rows, cols, True)
            if image is not None and follows:
                texel = _resampled(image, rows, cols, True)
                amb = (texel * app.ambient_weight + app.ambient_offset) * ambient_light
            elif image is not None:
                amb = (
                    np.asarray(app.ambient)
                    * ambient_light
                    * _resampled(image, rows, cols, True)
                    / np.maximum(np.asarray(app.base), 1e-6)
                )
            else:
                amb = np.zeros((rows, cols, 3)) + ambient
            if app.occlusion_texture is not None:
                occ = _resampled(self.texture_image(app.occlusion_texture), rows, cols, False)[:, :, :1]
                amb = amb * (1.0 + app.occlusion_strength * (occ - 1.0))
            total = (glow + amb).astype(np.float32)
            if not np.any(total > 0.0):
                return None
            radiance = self._bitmap(total, wrap_of(ref), ref, raw=True)
        else:
            total = emission + ambient
            if not np.any(total > 0.0):
                return None
            radiance = convert.rgb(total, linearize=False)
        return {"type": "area", "radiance": radiance, "sampling_weight": AMBIENT_SAMPLING_WEIGHT}

    def vertex_glow(self, linear_colors: np.ndarray, texcoords: bool = False) -> np.ndarray:
        """Per-vertex emitted radiance (emission plus ambient) of a vertex-coloured mesh, (N, 3) float32."""
        app = self.appearance(texcoords)
        ambient = (linear_colors[:, :3] * app.ambient_weight + app.ambient_offset) * self.ambient_light()
        return (ambient + np.asarray(app.emission)).astype(np.float32)

    def vertex_colors(self, linear_colors: np.ndarray, texcoords: bool = False) -> np.ndarray:
        """Linear per-vertex colours as the appearance model applies them: replacing or multiplying the base."""
        app = self.appearance(texcoords)
        if app.vertex_colors == "multiply":
            return (linear_colors[:, :3] * np.asarray(app.base)).astype(np.float32)
        return linear_colors[:, :3].astype(np.float32)

    def ambient_light(self) -> np.ndarray:
        """GL's ambient radiance: the global ambient plus every light's ambient term (see ``ambient_total``)."""
        if self._ambient is None:
            self._ambient = ambient_total(self.lights(), self.global_ambient)
        return self._ambient

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
        if not self.has_masks:
            return dict(COVERAGE_INTEGRATOR)
        # emitting surfaces (ambient, emission) must count as hits; only an environment must not
        hits = {**MASKED_COVERAGE_INTEGRATOR["hits"], "hide_emitters": self.has_environment()}
        return {**MASKED_COVERAGE_INTEGRATOR, "hits": hits}

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
        (plus the global ambient) are emitted by the surfaces (:meth:`current_area_emitter`);
        a scene without any light or emitter gets the GL engine's headlight.
        """
        if self._lights_converted:
            return
        self._lights_converted = True
        if not self.pending_lights and not self.emitters and self.headlight:
            self.add_emitter(convert.headlight_emitter(*self.camera_or_default()), "headlight")
        reference = self.reference_point()
        for light, matrix in self.pending_lights:
            if isinstance(light, AreaLight):  # an emitting shape, not a scene-level emitter
                for shape in convert.area_light_shapes(light, matrix):
                    shape["to_world"] = transform(shape["to_world"])
                    self.shapes[self.unique_name(type(light).__name__.lower())] = shape
                continue
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


# Its own renderer-specific attributes stay on their stacks here (other engines convert them to generic ones).
native_to(MitsubaEngine, "mitsuba.paint", BSDF)
