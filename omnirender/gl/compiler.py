"""Compiling a scene into a flat draw list (the GL technique's traversal).

Painters append draw items through :meth:`DrawListCompiler.submit`; nothing
here calls OpenGL.  The compiled items are cached per node occurrence and
version: a node whose version did not move, entered in an unchanged state, is
replayed from the cache without traversal, so a frame where one child of a
10,000-child node changed recompiles only that child.  Lights, the camera and
the background are pre-evaluated by an incremental walk cached the same way.
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable
from typing import Any

import numpy as np

from ..attributes import Background, Color, DrawStyle, Fog, Highlight, PBRMaterial, Texture
from ..core.camera import Camera
from ..core.component import MonoAttribute, PolyAttribute, RenderingComponent, Shape
from ..core.handler import Handler
from ..core.light import Light, LightSwitch
from ..core.mask import compile_mask
from ..core.program import compile_components
from ..core.technique import Technique
from ..core.transform import Transform
from ..scene.node import Node
from . import attributes as glattr
from .drawlist import DrawItem, DrawState
from .geometry import Geometry
from .shaders import ROW

__all__ = ["DrawListCompiler", "linear_rgb"]


def _lin(c: float) -> float:
    """One sRGB-encoded channel to linear (the IEC 61966-2-1 curve)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_rgb(rgb: Any) -> tuple[float, float, float]:
    """An sRGB colour (display values, as every engine reads colours) as linear values for lighting."""
    r, g, b = rgb[:3]
    return (_lin(float(r)), _lin(float(g)), _lin(float(b)))


_DEFAULT_POINT_SIZE = float(DrawStyle().point_size)  # without a DrawStyle, points get its default size


class _NodeEntry:
    """A node occurrence's compiled items, valid while its version and its own components are unchanged."""

    __slots__ = ("ref", "version", "own", "items")

    def __init__(self, node: Any, own: tuple, items: list[DrawItem]) -> None:
        self.ref = weakref.ref(node)
        self.version = node._version
        self.own = own
        self.items = items


class _Sequence:
    """A plain list of components compiled like the contents of an anonymous node."""

    __slots__ = ("_items", "_groups", "_version", "name", "path", "__weakref__")

    def __init__(self, components: Iterable[Any]) -> None:
        self._items = list(components)
        self._groups = frozenset()
        self._version = -1
        self.name = "components"
        self.path = "/components"

    def program(self) -> list:
        from ..core.program import ENTER, LEAVE, compile_components

        return [(ENTER, self), *compile_components(self._items, []), (LEAVE, -1)]


class DrawListCompiler:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: compile traversal, state capture, ``submit``."""

    def _prune_caches(self) -> None:
        """Drop cache entries of nodes that no longer exist (amortised: when a cache doubled)."""
        limit = self.__dict__.get("_prune_limit", 4096)
        if len(self._pre_cache) + len(self._node_cache) > limit:
            self._pre_cache = {k: v for k, v in self._pre_cache.items() if v[0]() is not None}
            self._node_cache = {k: v for k, v in self._node_cache.items() if v.ref() is not None}
            self._prune_limit = max(4096, 2 * (len(self._pre_cache) + len(self._node_cache)))

    def _begin_traversal(self, lights: list[tuple[Any, np.ndarray]]) -> None:
        ctx = self.context
        del ctx._matrices[1:]
        lights_set = ctx.poly_set(Light)
        self._placements[:] = lights  # engine.lights(): one entry per placement, as in the core
        for light, matrix in lights:
            self._pre_lights[id(light)] = light
            self._light_matrices[id(light)] = matrix
            lights_set.append(light)
        self._state_dirty = True
        self._surface_dirty = True

    def _end_traversal(self) -> None:
        lights_set = self.context.poly_set(Light)
        for light in self._pre_lights.values():
            for i in range(len(lights_set) - 1, -1, -1):
                if lights_set[i] is light:
                    del lights_set[i]
                    break
        self._pre_lights.clear()
        self._light_matrices.clear()
        self._placements.clear()

    def begin(self, root: Any) -> None:
        """Pre-evaluation for direct ``node.evaluate(engine)`` calls (uses the incremental walk)."""
        self._check_registry()
        self._preevaluated = True
        lights, camera, background = self._preevaluate(root)
        self.camera = camera
        self._scene_lights = lights
        self._scene_background = background
        self._saved_mask_fn = self._mask_fn
        if camera is not None and camera[0].mask and self._mask_fn is None:
            self._mask_fn = compile_mask(camera[0].mask)
        self._begin_traversal(lights)

    def end(self, root: Any) -> None:
        self._end_traversal()
        self._mask_fn = self._saved_mask_fn

    def _compile_node(self, node: Any, key: Any, forced: bool) -> None:
        groups = node._groups
        if groups and self._mask_fn is not None and not self._mask_fn(groups):
            return
        out = self._items
        entry = self._node_cache.get(key)
        same = entry is not None and entry.ref() is node
        if same and not forced and entry.version == node._version:
            out.extend(entry.items)
            return
        members = node._items
        own = tuple([x if x.__class__ is Node else (x, x._version) for x in members])
        sub_forced = forced or not same or entry.own != own
        start = len(out)
        stack = self._node_stack
        stack.append(node)
        undo: list[tuple[Any, Any]] = []
        push, pop, add, remove = self.push, self.pop, self.add, self.remove
        evaluate = self._ops[6]
        cache_get = self._node_cache.get
        for index, item in enumerate(members):
            if item.__class__ is Node or isinstance(item, Node):
                child_key = (key, index)
                if not sub_forced:
                    # inline cache hit: most children of a big node are unchanged
                    hit = cache_get(child_key)
                    if hit is not None and hit.version == item._version and hit.ref() is item:
                        out.extend(hit.items)
                        continue
                self._compile_node(item, child_key, sub_forced)
            elif isinstance(item, Shape):
                evaluate(item)
            elif isinstance(item, MonoAttribute):
                push(item)
                undo.append((pop, item.category))
            elif isinstance(item, PolyAttribute):
                add(item)
                undo.append((remove, item))
            elif isinstance(item, Technique):
                # a technique takes over the rest of the list, once per pass (core machinery, no caching inside)
                rest = compile_components(members[index + 1 :], [], f" in node {self.node_path}")
                self.run_technique(item, rest)
                break
            elif isinstance(item, Handler):
                self.install(item)
                undo.append((self.deinstall, item))
            else:
                raise TypeError(f"GLEngine: cannot evaluate {type(item).__name__} in node {self.node_path}")
        for fn, arg in reversed(undo):
            fn(arg)
        stack.pop()
        self._node_cache[key] = _NodeEntry(node, own, out[start:])

    def _preevaluate(self, root: Any) -> tuple[list, Any, Any]:
        """Lights (with world matrices), the first camera and the first Background, cached per node version."""
        lights, camera, background = self._pre_node(root, Background)
        return lights, camera, background

    def _pre_node(self, node: Any, background_cls: type) -> tuple[list, Any, Any]:
        groups = node._groups
        if groups and self._mask_fn is not None and not self._mask_fn(groups):
            return [], None, None
        entry = self._pre_cache.get(id(node))
        if entry is not None and entry[0]() is node and entry[1] == node._version and entry[3] is self._mask_fn:
            return entry[2]
        lights: list[tuple[Any, np.ndarray]] = []
        camera = None
        background = None
        m = None
        cache_get = self._pre_cache.get
        mask_fn = self._mask_fn
        for item in node._items:
            if item.__class__ is Node or isinstance(item, Node):
                hit = cache_get(id(item))
                if hit is not None and hit[1] == item._version and hit[3] is mask_fn and hit[0]() is item:
                    sub_lights, sub_camera, sub_bg = hit[2]
                    if not sub_lights and sub_camera is None and sub_bg is None:
                        continue
                else:
                    sub_lights, sub_camera, sub_bg = self._pre_node(item, background_cls)
                if sub_lights:
                    lights.extend(sub_lights if m is None else [(light, m @ lm) for light, lm in sub_lights])
                if camera is None and sub_camera is not None:
                    camera = sub_camera if m is None else (sub_camera[0], m @ sub_camera[1])
                if background is None:
                    background = sub_bg
            elif isinstance(item, Transform):
                mat = getattr(item, "matrix", None)
                if mat is not None:
                    m = mat if m is None else m @ mat
            elif isinstance(item, Light):
                lights.append((item, np.eye(4) if m is None else m))
            elif isinstance(item, Camera):
                if camera is None:
                    camera = (item, np.eye(4) if m is None else m)
            elif isinstance(item, background_cls):
                if background is None:
                    background = item
        result = (lights, camera, background)
        self._pre_cache[id(node)] = (weakref.ref(node), node._version, result, self._mask_fn)
        return result

    # -- what painters call ----------------------------------------------------

    def submit(
        self,
        geometry: Geometry,
        local: np.ndarray | None = None,
        kind: str | None = None,
        extra: Any = None,
        transparent: bool | None = None,
    ) -> DrawItem:
        """Append a draw item for ``geometry`` in the current state (model matrix, material, GL state).

        ``local`` is a shape-local matrix applied after the model matrix (the
        native painters scale a unit mesh with it).  Painters call this; it
        issues no GL call.
        """
        if self._state_dirty:
            self._resolve_state()
        if self._surface_dirty:
            self._resolve_surface()
        m = self.context.model_matrix()
        if local is not None:
            m = m @ local
        row = np.empty(ROW, np.float32)
        row[:16] = m.T.ravel()
        row[16:] = self._surface_row
        row[37] = self._point_size
        if kind is None:
            kind = self._kind_for(geometry)
        if transparent is None:
            transparent = self._blend_on or row[19] < 1.0 or geometry.translucent
        cull = None
        if geometry.closed and not transparent and kind == "mesh":
            base = self._state_base
            if base[3] == "none" and not base[10] and not base[7]:
                # a closed opaque surface never shows its back faces: cull them (mirrored instances: the front)
                cull = "back" if np.linalg.det(m[:3, :3]) > 0.0 else "front"
        state = self._state_for(kind, geometry, extra, cull)
        stack = self._node_stack
        item = DrawItem(geometry, state, row, transparent, stack[-1] if stack else None)
        self._items.append(item)
        return item

    def _kind_for(self, geometry: Geometry) -> str:
        mode = geometry.mode
        if mode == "triangles":
            return "points" if self._fill == "points" else "mesh"
        return mode

    def _resolve_state(self) -> None:
        mono = self.context._mono

        def top(cat: type) -> Any:
            s = mono.get(cat)
            return s[-1] if s else None

        style = top(DrawStyle)
        depth = top(glattr.DepthTest)
        dmask = top(glattr.DepthMask)
        blend = top(glattr.Blend)
        cull = top(glattr.CullFace)
        offset = top(glattr.PolygonOffset)
        cmask = top(glattr.ColorMask)
        stest = top(glattr.StencilTest)
        sop = top(glattr.StencilOp)
        fog = top(Fog)
        texture = top(Texture)
        if texture is not None:
            checked = self._checked_textures.get(id(texture))
            if checked is None or checked[0]() is not texture or checked[1] != texture._version:
                try:
                    h, w = texture.image_array().shape[:2]
                except (OSError, ValueError) as exc:  # a missing or unreadable image file: say where it is used
                    where = f" in node {self.node_path}" if self.node_path else ""
                    raise type(exc)(
                        f"GLEngine: {exc}{where}; fix the path or pass an array (om.Texture(numpy_array))"
                    ) from None
                self.check_texture_size(f"Texture (image {w}x{h})", (w, h), self.max_texture_size)
                if len(self._checked_textures) > 4096:
                    self._checked_textures.clear()
                self._checked_textures[id(texture)] = (weakref.ref(texture), texture._version)
        switch = top(LightSwitch)
        self._fill = style.mode if style is not None else "filled"
        # without a DrawStyle: DrawStyle's default (1 px), as in POV-Ray and Mitsuba
        self._point_size = float(style.point_size) if style is not None else _DEFAULT_POINT_SIZE
        cull_mode = cull.mode if cull is not None else (style.cull if style is not None else "none")
        blend_key = (blend.src, blend.dst, blend.equation) if blend is not None and blend.enabled else None
        self._blend_on = blend_key is not None
        stencil = None
        if stest is not None and stest.enabled:
            s = sop or glattr.StencilOp()
            stencil = (stest.func, stest.ref, stest.mask, s.fail, s.zfail, s.zpass, s.write_mask)
        fog_key = None
        if fog is not None:
            mode = {"linear": 0.0, "exp": 1.0, "exp2": 2.0}[fog.mode]
            fog_key = (linear_rgb(fog.color), float(fog.start), float(fog.end), float(fog.density), mode)
        self._state_base = (
            ("less" if depth is None else depth.func) if depth is None or depth.enabled else None,
            True if dmask is None else dmask.enabled,
            blend_key,
            cull_mode,
            (offset.factor, offset.units) if offset is not None else None,
            (cmask.red, cmask.green, cmask.blue, cmask.alpha) if cmask is not None else (True, True, True, True),
            stencil,
            self._fill == "wireframe",
            float(style.line_width) if style is not None else 1.0,
            texture,
            tuple(plane for _, plane in self._clips),
            fog_key,
            switch,
            style is not None and style.shading == "flat",
        )
        self._state_dirty = False

    def _state_for(self, kind: str, geometry: Geometry, extra: Any, cull_override: str | None = None) -> DrawState:
        base = self._state_base
        texture = base[9]
        features = []
        if geometry.colors is not None:
            features.append(("VCOLOR", True))
        if texture is not None and geometry.texcoords is not None and kind == "mesh":
            features.append(("TEXTURE", True))
        if base[13] and kind == "mesh":
            features.append(("FLAT", True))
        if base[10]:
            features.append(("NCLIP", len(base[10])))
        if base[11] is not None:
            features.append(("FOG", True))
        if kind == "points" and geometry.sizes is not None:
            features.append(("VSIZE", True))
        key = (kind, tuple(features), extra, base, cull_override)
        state = self._states.get(key)
        if state is None:
            depth_func, depth_mask, blend, cull, offset, cmask, stencil, wire, width, tex, clip, fog, switch, _ = base
            state = DrawState(
                kind=kind,
                features=tuple(features),
                depth_func=depth_func,
                depth_mask=depth_mask,
                blend=blend,
                cull=cull_override or cull,
                polygon_offset=offset,
                color_mask=cmask,
                stencil=stencil,
                wireframe=wire and kind == "mesh",
                line_width=width,
                texture=tex if ("TEXTURE", True) in features else None,
                clip=clip,
                fog=fog,
                switch=switch,
                extra=extra,
                overlay=kind in ("text",),
            )
            if len(self._states) > 4096:  # e.g. text labels that change every frame
                self._states.clear()
            self._states[key] = state
        return state

    def _resolve_surface(self) -> None:
        surface = self._surface
        material = None
        color = None
        for attr in reversed(surface):
            if attr.__class__ is Color or isinstance(attr, Color):
                if color is None:
                    color = attr
            else:
                material = attr
                break
        stack = self.context._mono.get(Highlight)
        highlight = stack[-1] if stack else None
        key = (
            id(material),
            material._version if material is not None else 0,
            id(highlight),
            highlight._version if highlight is not None else 0,
        )
        memo = self._surface_memo
        base = memo.get(key)
        if base is None or base[0] is not material:
            base = (material, self._material_row(material, highlight))
            if len(memo) > 256:
                memo.clear()
            memo[key] = base
        row = base[1]
        if color is not None:
            row = row.copy()
            row[0:4] = (_lin(color._r), _lin(color._g), _lin(color._b), color._a * row[3])
            if not isinstance(material, PBRMaterial):
                row[15] = 1.0  # colour material: ambient follows the colour
        self._surface_row = row
        self._surface_dirty = False

    def _material_row(self, material: Any, highlight: Any) -> np.ndarray:
        """The 24 material floats of an instance row (colour, specular, emission, ambient, highlight, extra).

        Surface colours are display (sRGB) values, as in the other engines; the
        shaders light in linear space, so they are linearised here.
        """
        row = np.zeros(ROW - 16, np.float32)
        if isinstance(material, PBRMaterial):
            row[0:4] = (*linear_rgb(material.base_color), material.opacity)
            row[8:12] = (*linear_rgb(material.emission), 1.0)
            row[12:16] = (0.0, 0.0, 0.0, material.roughness)
            row[20] = material.metallic
        elif material is not None:
            row[0:4] = (*linear_rgb(material.diffuse), material.opacity)
            row[4:8] = (*linear_rgb(material.specular), material.shininess)
            row[8:12] = (*linear_rgb(material.emission), 0.0)
            row[12:16] = (*linear_rgb(material.ambient), 0.0)
        else:
            row[0:4] = (*linear_rgb((0.8, 0.8, 0.8)), 1.0)
            row[4:8] = (0.0, 0.0, 0.0, 32.0)
            row[12:16] = (0.0, 0.0, 0.0, 1.0)  # ambient follows the colour
        if highlight is not None:
            row[16:20] = (*linear_rgb(highlight.color), 1.0)
        return row

    # -- draw ------------------------------------------------------------------

    def compile(self, scene: Any, mask: Any = None) -> list[DrawItem]:
        """Compile ``scene`` (a Node or components) into the draw list; cached while nothing changed."""
        if mask is not None:
            self.mask = mask
        if not hasattr(scene, "_items"):
            scene = _Sequence([scene] if isinstance(scene, RenderingComponent) else scene)
        mask_key = self._mask
        c = self._compiled
        if c is not None and c[0]() is scene and c[1] == scene._version and c[2] == mask_key:
            self.stats["compiled"] = False
            return self._list
        self._check_registry()
        saved_mask_fn = self._mask_fn
        lights, camera, background = self._preevaluate(scene)
        self.camera = camera
        self._scene_lights = lights
        self._scene_background = background
        if camera is not None and camera[0].mask and self._mask_fn is None:
            self._mask_fn = compile_mask(camera[0].mask)
        full_key = (mask_key, camera[0].mask if camera is not None else None)
        if c is None or c[0]() is not scene or c[2] != mask_key or getattr(self, "_full_key", None) != full_key:
            self._node_cache.clear()
        self._full_key = full_key
        self._begin_traversal(lights)
        items: list[DrawItem] = []
        self._items = items
        self._running += 1
        try:
            self._compile_node(scene, (), False)
        except BaseException as exc:
            path = self.node_path
            self._reset()
            self._surface.clear()
            self._clips.clear()
            self._node_cache.clear()
            self._compiled = None
            # like Engine.run: a painter's or simplifier's bad-input error names the node it happened in
            if path and type(exc) in (ValueError, TypeError) and path not in str(exc):
                raise type(exc)(f"{exc} (in node {path})") from exc
            raise
        finally:
            self._running -= 1
            self._items = self._immediate
            self._end_traversal()
            self._mask_fn = saved_mask_fn
        self._compiled = (weakref.ref(scene), scene._version, mask_key)
        self._prune_caches()
        self._install_list(items)
        self.stats["compiled"] = True
        return items
