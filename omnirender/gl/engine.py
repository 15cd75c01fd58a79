"""The OpenGL engine: compiles a scene into a draw list, then draws it with instancing.

Rendering is COMPILE then DRAW (DESIGN.md, performance model).  Compiling
runs the GL technique's traversal: painters append draw items to a flat list
instead of issuing GL calls.  The list is cached per node and version, so a
frame whose scene did not change replays the GPU batches without any
traversal, and a frame where one subtree changed recompiles only that
subtree and rewrites only the changed instance rows.  Drawing is the
technique's two passes: opaque batches (one instanced call per geometry and
state), then transparent items sorted back to front with blending on and
depth writes off, then 2D overlays (text) without depth test.
"""

from __future__ import annotations

import contextlib
import math
import weakref
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from ..attributes import Background, Color, DrawStyle, Fog, Highlight, PBRMaterial, Texture
from ..core.camera import Camera
from ..core.component import MonoAttribute, PolyAttribute, Shape
from ..core.engine import Engine
from ..core.handler import Handler
from ..core.light import Light, LightSwitch
from ..core.mask import compile_mask
from ..core.technique import Technique
from ..core.transform import Transform
from ..image import Image
from . import attributes as glattr
from .context import (
    GLError,
    RawGL,
    check_size,
    clear_stencil,
    create_context,
    depth_stencil_framebuffer,
    set_masks,
)
from .drawlist import Batch, DrawItem, DrawState, plan_batches, uniform_material
from .geometry import Geometry, GeometryCache, unit_box, unit_cylinder, unit_sphere
from .lighting import LightUniforms
from .resources import gpu_call
from .shaders import INSTANCE_ATTRIBUTES, INSTANCE_FORMAT, ROW, ProgramCache

__all__ = ["GLEngine", "GLTechnique", "DEFAULT_BACKGROUND"]

#: Default clear colour (sRGB): a neutral dark grey.
DEFAULT_BACKGROUND = (0.16, 0.16, 0.17, 1.0)

_DEPTH_FUNCS = {
    "never": "0",
    "less": "<",
    "equal": "==",
    "lequal": "<=",
    "greater": ">",
    "notequal": "!=",
    "gequal": ">=",
    "always": "1",
}
_GL_CLIP_DISTANCE0 = 0x3000


class GLTechnique(Technique):
    """The default GL technique: compile the graph into draw items, then draw in two passes.

    Pass 1 draws opaque items, pass 2 the transparent items found while
    compiling, sorted back to front; 2D overlays come last.  The traversal
    itself is one pass that only collects (painters append draw items), so it
    can be cached and replayed.
    """

    __slots__ = ()

    def __init__(self) -> None:
        super().__init__(service="gl.paint", passes=1)


class _NodeEntry:
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


class GLEngine(Engine):
    """Real-time OpenGL engine (moderngl): headless EGL by default, or a given moderngl context.

    ``GLEngine(size=(w, h), samples=4)``; ``engine.render(scene) -> om.Image``
    renders frame after frame, keeping GPU resources between frames.
    ``samples=0`` turns multisampling off.
    """

    service = "gl.paint"
    #: Drawers for draw-item kinds that are not plain instanced geometry (text, volumes), by kind.
    _default_drawers: dict[str, Any] = {}

    def __init__(
        self,
        size: tuple[int, int] = (640, 480),
        samples: int = 4,
        context: Any = None,
        *,
        background: Any = None,
        technique: Technique | None = None,
        on_missing: str = "raise",
        mask: Any = None,
    ) -> None:
        from . import _load

        _load()  # painters register on first use
        super().__init__(technique=technique or GLTechnique(), on_missing=on_missing, mask=mask)
        self.ctx = context if context is not None else create_context()
        self._own_context = context is None
        self._size = check_size(size, self.ctx)
        if samples < 0:
            raise ValueError(f"GLEngine: samples must be >= 0, got {samples}")
        self._samples = min(int(samples), int(self.ctx.max_samples)) if samples else 0
        self.background = background
        self.programs = ProgramCache(self.ctx)
        self.geometry_cache = GeometryCache()
        self.raw = RawGL()
        self.unit = {"sphere": unit_sphere(), "box": unit_box(), "cylinder": unit_cylinder()}
        self._targets: dict[str, Any] = {}
        self._target_stack: list[Any] = []
        self._make_targets()
        # compile state
        self._items: list[DrawItem] = []
        self._immediate: list[DrawItem] = []
        self._node_cache: dict[Any, _NodeEntry] = {}
        self._pre_cache: dict[int, tuple[Any, int, Any]] = {}
        self._compiled: tuple[Any, int, Any] | None = None  # (scene ref, version, mask key)
        self._list: list[DrawItem] = []
        self._slots: list[Any] = []
        self._batches: dict[tuple, Batch] = {}
        self._batch_order: list[Batch] = []
        self._others: list[DrawItem] = []
        self._scene_lights: list[tuple[Any, np.ndarray]] = []
        self._scene_background: Any = None
        self._surface: list[Any] = []
        self._clips: list[tuple[Any, tuple[float, float, float, float]]] = []
        self._state_dirty = True
        self._surface_dirty = True
        self._state_base: tuple = ()
        self._states: dict[tuple, DrawState] = {}
        self._surface_row = np.zeros(ROW - 16, np.float32)
        self._surface_memo: dict[tuple, tuple[Any, np.ndarray]] = {}
        self._point_size = 1.0
        self._blend_on = False
        self._fill = "filled"
        self._transient: dict[Any, tuple[Any, Any, int]] = {}
        self._gl_state: dict[str, Any] = {}
        self._drawers: dict[str, Any] = GLEngine._default_drawers
        self._bounds: tuple[np.ndarray, np.ndarray] | None = None
        self.stats: dict[str, Any] = {}
        self._view = np.eye(4)
        self._proj = np.eye(4)
        self._camera_used: Camera | None = None
        with self.current():
            self.ctx.enable(self.ctx.PROGRAM_POINT_SIZE)

    # -- targets -----------------------------------------------------------
    @contextlib.contextmanager
    def current(self) -> Iterator[Any]:
        """Make the engine's context current for GL calls (and leave it current afterwards).

        moderngl's ``with ctx:`` restores the previously current context on exit,
        which breaks when nested on the same context; an engine that owns its
        context therefore only makes it current.  A wrapped context (a window's)
        is assumed to be current already.
        """
        if self._own_context:
            self.ctx.mglo.__enter__()
        yield self.ctx

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels; assigning resizes the framebuffers."""
        return self._size

    @size.setter
    def size(self, value: tuple[int, int]) -> None:
        value = check_size(value, self.ctx)
        if value != self._size:
            self._size = value
            self._make_targets()

    @property
    def samples(self) -> int:
        """Multisample count (0: off)."""
        return self._samples

    def _make_targets(self) -> None:
        with self.current():
            self._create_targets()

    def _create_targets(self) -> None:
        seen = set()
        for obj in self._targets.values():
            if id(obj) not in seen:
                seen.add(id(obj))
                obj.release()
        self._targets.clear()
        ctx, size = self.ctx, self._size
        t = self._targets
        t["color"] = gpu_call(ctx.renderbuffer, size, 4, what="the colour buffer")
        t["depth"] = gpu_call(ctx.depth_renderbuffer, size, what="the depth buffer")
        t["fbo"] = ctx.framebuffer(t["color"], t["depth"])
        if self._samples:
            t["ms_color"] = gpu_call(ctx.renderbuffer, size, 4, samples=self._samples, what="the colour buffer")
            target = "ms_fbo"
            color = t["ms_color"]
        else:
            target = "draw_fbo"
            color = t["color"]
        # draw into a framebuffer with a depth-stencil attachment (StencilTest needs it); fall back to depth only
        made = depth_stencil_framebuffer(ctx, self.raw, color, size, self._samples)
        if made is not None:
            t[target] = made[0]
            self._stencil_rbo = made[1]
            self.has_stencil = True
            if not self._samples:
                t["fbo"].release()
                t["fbo"] = made[0]  # draw and read the same framebuffer: no copy per frame
        else:
            if self._samples:
                t["ms_depth"] = gpu_call(ctx.depth_renderbuffer, size, samples=self._samples, what="the depth buffer")
                t[target] = ctx.framebuffer(color, t["ms_depth"])
            else:
                t[target] = t["fbo"]
            self.has_stencil = False

    @property
    def framebuffer(self) -> Any:
        """The framebuffer drawn into (multisampled when samples > 0)."""
        if self._target_stack:
            return self._target_stack[-1].fbo
        return self._targets["ms_fbo" if self._samples else "draw_fbo"]

    # -- compile -------------------------------------------------------------
    def compile(self, scene: Any, mask: Any = None) -> list[DrawItem]:
        """Compile ``scene`` (a Node or components) into the draw list; cached while nothing changed."""
        if mask is not None:
            self.mask = mask
        if not hasattr(scene, "_items"):
            scene = _Sequence(scene)
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
        except BaseException:
            self._reset()
            self._surface.clear()
            self._clips.clear()
            self._node_cache.clear()
            self._compiled = None
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

    def begin(self, root: Any) -> None:
        """Pre-evaluation for direct ``node.evaluate(engine)`` calls (uses the incremental walk)."""
        self._check_registry()
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
        own = tuple(x if hasattr(x, "_items") else (x, x._version) for x in members)
        sub_forced = forced or not same or entry.own != own
        start = len(out)
        stack = self._node_stack
        stack.append(node)
        if any(isinstance(x, Technique) for x in members):
            # A technique takes over the rest of the list: let the core run it (no caching inside).
            stack.pop()
            Engine.run_program(self, node.program())
        else:
            undo: list[tuple[Any, Any]] = []
            push, pop, add, remove = self.push, self.pop, self.add, self.remove
            evaluate = self._ops[6]
            for index, item in enumerate(members):
                if hasattr(item, "_items"):
                    self._compile_node(item, (key, index), sub_forced)
                elif isinstance(item, Shape):
                    evaluate(item)
                elif isinstance(item, MonoAttribute):
                    push(item)
                    undo.append((pop, item.category))
                elif isinstance(item, PolyAttribute):
                    add(item)
                    undo.append((remove, item))
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
        for item in node._items:
            if hasattr(item, "_items"):
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
        state = self._state_for(kind, geometry, extra)
        if transparent is None:
            transparent = self._blend_on or row[19] < 1.0 or geometry.translucent
        item = DrawItem(geometry, state, row, transparent, "")
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
        switch = top(LightSwitch)
        self._fill = style.mode if style is not None else "filled"
        self._point_size = float(style.point_size) if style is not None else 4.0
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
            fog_key = (tuple(fog.color), float(fog.start), float(fog.end), float(fog.density), mode)
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

    def _state_for(self, kind: str, geometry: Geometry, extra: Any) -> DrawState:
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
        key = (kind, tuple(features), extra, base)
        state = self._states.get(key)
        if state is None:
            depth_func, depth_mask, blend, cull, offset, cmask, stencil, wire, width, tex, clip, fog, switch, _ = base
            state = DrawState(
                kind=kind,
                features=tuple(features),
                depth_func=depth_func,
                depth_mask=depth_mask,
                blend=blend,
                cull=cull,
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
            row[0:4] = (color._r, color._g, color._b, color._a * row[3])
            if not isinstance(material, PBRMaterial):
                row[15] = 1.0  # colour material: ambient follows the colour
        self._surface_row = row
        self._surface_dirty = False

    def _material_row(self, material: Any, highlight: Any) -> np.ndarray:
        """The 24 material floats of an instance row (colour, specular, emission, ambient, highlight, extra)."""
        row = np.zeros(ROW - 16, np.float32)
        if isinstance(material, PBRMaterial):
            row[0:4] = (*material.base_color, material.opacity)
            row[8:12] = (*material.emission, 1.0)
            row[12:16] = (0.0, 0.0, 0.0, material.roughness)
            row[20] = material.metallic
        elif material is not None:
            row[0:4] = (*material.diffuse, material.opacity)
            row[4:8] = (*material.specular, material.shininess)
            row[8:12] = (*material.emission, 0.0)
            row[12:16] = (*material.ambient, 0.0)
        else:
            row[0:4] = (0.8, 0.8, 0.8, 1.0)
            row[4:8] = (0.0, 0.0, 0.0, 32.0)
            row[12:16] = (0.0, 0.0, 0.0, 1.0)  # ambient follows the colour
        if highlight is not None:
            row[16:20] = (*highlight.color, 1.0)
        return row

    # -- draw ------------------------------------------------------------------
    def render(
        self,
        scene: Any = None,
        *,
        mask: Any = None,
        background: Any = None,
        read_depth: bool = True,
    ) -> Image:
        """Compile (if the scene changed) and draw ``scene``; returns an :class:`om.Image`.

        Without a scene, draws what was evaluated into the engine directly
        (``engine.push(...)``, ``engine.eval(shape)``, ...) and clears that list;
        such a frame uses the auto-fit camera and a headlight.
        """
        with self.current():
            if scene is not None:
                self.compile(scene, mask=mask)
            else:
                # immediate mode: what was evaluated directly, seen by the auto-fit camera under a headlight
                self._install_list(self._immediate)
                self._immediate = []
                self._items = self._immediate
                self._compiled = None
                self.camera = None
                self._scene_lights = []
                self._scene_background = None
            self.draw(background=background)
            return self.read(read_depth=read_depth)

    def _install_list(self, items: list[DrawItem]) -> None:
        """Make ``items`` the draw list: update batches in place when possible, else rebuild them."""
        old = self._list
        self._bounds = None
        if len(items) == len(old) and old:
            changed = [i for i, (a, b) in enumerate(zip(items, old, strict=False)) if a is not b]
            slots = self._slots
            ok = True
            for i in changed:
                a, b = items[i], old[i]
                if a.geometry is not b.geometry or a.state is not b.state or a.transparent != b.transparent:
                    ok = False
                    break
            if ok:
                others = self._others
                need_others = False
                for i in changed:
                    slot = slots[i]
                    if slot is None:
                        need_others = True
                        continue
                    batch, index = slot
                    batch.items[index] = items[i]
                    row = items[i].row
                    batch.rows[index] = row
                    batch.mark(index)
                    if batch.uniform and not (row[20:40] == batch.rows[0, 20:40]).all():
                        batch.uniform = False
                if need_others:
                    self._others = [it for it in items if it.transparent or it.state.overlay]
                else:
                    self._others = others
                self._list = items
                self.stats["incremental"] = len(changed)
                return
        self.stats["incremental"] = None
        groups, plan, others = plan_batches(items)
        batches: dict[tuple, Batch] = {}
        for key, group in groups.items():
            batch = self._batches.pop(key, None)
            if batch is None:
                batch = Batch(key[0], key[1])
            batch.items = group
            batch.rows = np.stack([it.row for it in group]) if len(group) > 1 else group[0].row[None, :].copy()
            batch.dirty = (0, len(group))
            batch.uniform = uniform_material(batch.rows)
            batches[key] = batch
        for batch in self._batches.values():
            batch.release()
        self._batches = batches
        self._batch_order = list(batches.values())
        self._slots = [None if s is None else (batches[s[0]], s[1]) for s in plan]
        self._others = others
        self._list = items
        used = {id(it.geometry) for it in items}
        for transient in list(self._transient):
            if transient[0] not in used:
                buf, vao, _ = self._transient.pop(transient)
                vao.release()
                buf.release()
        self.geometry_cache.sweep(used)
        for geom in list(self._uploaded()):
            if id(geom) not in used and not geom.persistent:
                geom.release()

    def _uploaded(self) -> list[Geometry]:
        return [g for g in self.__dict__.setdefault("_uploaded_set", weakref.WeakSet())]

    def _ensure_uploaded(self, geometry: Geometry) -> None:
        if geometry.buffers is None:
            geometry.upload(self.ctx)
            self.__dict__.setdefault("_uploaded_set", weakref.WeakSet()).add(geometry)

    def scene_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World-space (min, max) of the compiled draw list, or None when it is empty."""
        if self._bounds is not None:
            return self._bounds
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        for item in self._list:
            if item.state.overlay:
                continue
            g = item.geometry
            b0, b1 = g.bounds
            corners = np.array([[x, y, z, 1.0] for x in (b0[0], b1[0]) for y in (b0[1], b1[1]) for z in (b0[2], b1[2])])
            m = item.row[:16].reshape(4, 4).T.astype(np.float64)
            w = corners @ m.T
            lo = np.minimum(lo, w[:, :3].min(axis=0))
            hi = np.maximum(hi, w[:, :3].max(axis=0))
        if not np.all(np.isfinite(lo)):
            return None
        self._bounds = (lo, hi)
        return self._bounds

    def _camera_matrices(self) -> tuple[Camera, np.ndarray, np.ndarray]:
        w, h = self._size
        aspect = w / h
        if self.camera is not None:
            camera, world = self.camera
            view = camera.view_matrix() @ np.linalg.inv(world)
        else:
            camera = self.default_camera()
            view = camera.view_matrix()
        return camera, view, camera.projection_matrix(aspect)

    def default_camera(self) -> Camera:
        """Auto-fit: look at the compiled scene's bounds from +z (vertical fov 35 degrees)."""
        bounds = self.scene_bounds()
        if bounds is None:
            return Camera.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
        lo, hi = bounds
        center = (lo + hi) / 2.0
        radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-6)
        fov = 35.0
        w, h = self._size
        half = math.radians(fov) / 2.0
        if w < h:
            half = math.atan(math.tan(half) * w / h)
        dist = radius / math.sin(half) * 1.02
        near = max(dist - radius * 1.5, dist * 1e-3)
        far = dist + radius * 1.5
        return Camera.look_at(tuple(center + (0.0, 0.0, dist)), tuple(center), (0, 1, 0), fov=fov, near=near, far=far)

    def view_matrix(self) -> np.ndarray | None:
        if self.camera is None:
            return None
        return super().view_matrix()

    def clear_color(self, background: Any = None) -> tuple[float, float, float, float]:
        """The sRGB clear colour: ``background`` argument, scene Background, engine default."""
        bg = background if background is not None else self.background
        if bg is None and self._scene_background is not None:
            bg = self._scene_background
        if bg is None:
            return DEFAULT_BACKGROUND
        color = tuple(getattr(bg, "color", bg))
        if len(color) == 3:
            color = (*color, 1.0)
        lin = np.clip(np.asarray(color[:3], dtype=np.float64), 0.0, 1.0)
        srgb = np.where(lin <= 0.0031308, lin * 12.92, 1.055 * lin ** (1 / 2.4) - 0.055)
        return (float(srgb[0]), float(srgb[1]), float(srgb[2]), float(color[3]))

    def draw(self, background: Any = None, clear: bool = True) -> None:
        """Draw the installed draw list into the framebuffer (opaque, transparent sorted, overlays).

        ``clear=False`` draws over what the framebuffer holds (compositing several renderers).
        """
        with self.current():
            self._draw(background, clear)

    def _draw(self, background: Any, clear: bool) -> None:
        ctx = self.ctx
        fbo = self.framebuffer
        fbo.use()
        ctx.viewport = (0, 0, *self._size)
        self._gl_state.clear()
        set_masks(ctx, self.raw, fbo, color=(True, True, True, True), depth=True)
        if clear:
            fbo.clear(*self.clear_color(background), depth=1.0)
            if self.has_stencil and not self._target_stack:
                clear_stencil(self.raw, 0)
        ctx.enable(ctx.PROGRAM_POINT_SIZE)
        camera, view, proj = self._camera_matrices()
        self._camera_used = camera
        self._view = view
        self._proj = proj
        self._frame_uniforms = {
            "u_view": view.T.astype(np.float32).tobytes(),
            "u_proj": proj.T.astype(np.float32).tobytes(),
        }
        self._light_cache: dict[int, LightUniforms] = {}
        calls = 0
        for batch in self._batch_order:
            calls += self._draw_batch(batch)
        others = self._others
        if others:
            calls += self._draw_others(others)
        self._restore_defaults()
        self.stats["draw_calls"] = calls
        self.stats["batches"] = len(self._batch_order)
        self.stats["items"] = len(self._list)
        err = ctx.error
        if err != "GL_NO_ERROR":
            if "OUT_OF_MEMORY" in err:
                raise GLError("GLEngine: the GPU ran out of memory while drawing; reduce the scene or image size")
            raise GLError(f"GLEngine: OpenGL reported {err} while drawing")

    def _lights_for(self, switch: Any) -> LightUniforms:
        key = id(switch)
        lu = self._light_cache.get(key)
        if lu is None:
            lights = self._scene_lights
            if switch is not None:
                lights = [(light, m) for light, m in lights if switch.allows(light)]
            lu = LightUniforms(lights, self._view, headlight=not self._scene_lights)
            self._light_cache[key] = lu
        return lu

    def _program(self, state: DrawState) -> Any:
        return self.programs.get(state.kind, state.features)

    def _set_uniforms(self, prog: Any, state: DrawState) -> None:
        for name, data in self._frame_uniforms.items():
            u = prog.get(name, None)
            if u is not None:
                u.write(data)
        self._lights_for(state.switch).apply(prog)
        u = prog.get("u_ortho", None)
        if u is not None:
            u.value = 1 if self._camera_used is not None and self._camera_used.is_orthographic else 0
        if state.clip:
            prog["u_clip"].write(np.asarray(state.clip, np.float32).tobytes())
        if state.fog is not None:
            color, start, end, density, mode = state.fog
            prog["u_fog"].value = (start, end, density, mode)
            prog["u_fog_color"].value = color
        if state.kind == "lines":
            prog["u_viewport"].value = (self._size[0] / 2.0, self._size[1] / 2.0)
            prog["u_line_width"].value = float(state.line_width)
        if state.texture is not None:
            self._texture(state.texture).use(0)
            u = prog.get("u_texture", None)
            if u is not None:
                u.value = 0

    def _texture(self, attr: Any) -> Any:
        cache = self.__dict__.setdefault("_textures", {})
        entry = cache.get(id(attr))
        if entry is not None and entry[0]() is attr and entry[1] == attr._version:
            return entry[2]
        if entry is not None:
            entry[2].release()
        img = np.ascontiguousarray(attr.image_array()[::-1])
        h, w = img.shape[:2]
        tex = gpu_call(self.ctx.texture, (w, h), 4, img.tobytes(), what="a texture")
        mipmap = attr.mipmap
        if mipmap:
            tex.build_mipmaps()
        lin = attr.filter == "linear"
        mag = self.ctx.LINEAR if lin else self.ctx.NEAREST
        if mipmap:
            minf = self.ctx.LINEAR_MIPMAP_LINEAR if lin else self.ctx.NEAREST_MIPMAP_NEAREST
        else:
            minf = mag
        tex.filter = (minf, mag)
        tex.repeat_x = tex.repeat_y = attr.wrap != "clamp"
        if attr.wrap == "mirror" and self.raw.available:
            # moderngl has no mirrored-repeat switch: set GL_MIRRORED_REPEAT on the bound texture
            tex.use(0)
            for pname in (0x2802, 0x2803):  # GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T
                self.raw.glTexParameteri(0x0DE1, pname, 0x8370)
        cache[id(attr)] = (weakref.ref(attr), attr._version, tex)
        return tex

    def _apply_state(self, state: DrawState, *, blend_override: Any = None, depth_mask: Any = None) -> None:
        ctx = self.ctx
        cur = self._gl_state
        depth = state.depth_func
        if cur.get("depth") != depth:
            if depth is None:
                ctx.disable(ctx.DEPTH_TEST)
            else:
                ctx.enable(ctx.DEPTH_TEST)
                ctx.depth_func = _DEPTH_FUNCS[depth]
            cur["depth"] = depth
        dmask = state.depth_mask if depth_mask is None else (depth_mask and state.depth_mask)
        if cur.get("dmask") != dmask:
            set_masks(ctx, self.raw, self.framebuffer, depth=dmask)
            cur["dmask"] = dmask
        blend = state.blend if blend_override is None else blend_override
        if cur.get("blend") != blend:
            if blend is None:
                ctx.disable(ctx.BLEND)
            else:
                ctx.enable(ctx.BLEND)
                src, dst, eq = blend
                ctx.blend_func = (_factor(ctx, src), _factor(ctx, dst))
                ctx.blend_equation = _equation(ctx, eq)
            cur["blend"] = blend
        cull = cur.get("cull_override") or state.cull
        if cur.get("cull") != cull:
            if cull == "none":
                ctx.disable(ctx.CULL_FACE)
            else:
                ctx.enable(ctx.CULL_FACE)
                ctx.cull_face = cull
            cur["cull"] = cull
        if cur.get("offset") != state.polygon_offset:
            ctx.polygon_offset = state.polygon_offset or (0.0, 0.0)
            cur["offset"] = state.polygon_offset
        if cur.get("cmask") != state.color_mask:
            set_masks(ctx, self.raw, self.framebuffer, color=state.color_mask)
            cur["cmask"] = state.color_mask
        if cur.get("stencil", None) != state.stencil:
            self.raw.stencil(ctx, state.stencil)
            cur["stencil"] = state.stencil
        if cur.get("wire") != state.wireframe:
            ctx.wireframe = bool(state.wireframe)
            cur["wire"] = state.wireframe
        if state.wireframe and cur.get("width") != state.line_width:
            ctx.line_width = float(state.line_width)
            cur["width"] = state.line_width
        nclip = len(state.clip) if state.clip else 0
        if cur.get("nclip", 0) != nclip:
            for i in range(6):
                if i < nclip:
                    ctx.enable_direct(_GL_CLIP_DISTANCE0 + i)
                else:
                    ctx.disable_direct(_GL_CLIP_DISTANCE0 + i)
            cur["nclip"] = nclip

    def _restore_defaults(self) -> None:
        """State preservation: leave the context as a plain moderngl user expects it."""
        ctx = self.ctx
        ctx.disable(ctx.BLEND | ctx.CULL_FACE)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.depth_func = "<"
        ctx.wireframe = False
        ctx.polygon_offset = (0.0, 0.0)
        set_masks(ctx, self.raw, self.framebuffer, color=(True, True, True, True), depth=True)
        if self._gl_state.get("stencil") is not None:
            self.raw.stencil(ctx, None)
        for i in range(self._gl_state.get("nclip", 0)):
            ctx.disable_direct(_GL_CLIP_DISTANCE0 + i)
        self._gl_state.clear()

    def _vao(self, geometry: Geometry, program: Any, buffer: Any, kind: str, compact: bool = False) -> Any:
        self._ensure_uploaded(geometry)
        content = geometry.content(program)
        if buffer is None:
            pass
        elif compact:
            content.append((buffer, "16f 4f/i", "i_model", "i_color"))
        else:
            content.append((buffer, INSTANCE_FORMAT, *INSTANCE_ATTRIBUTES))
        index = geometry.buffers.get("index") if kind != "points" else None
        return self.ctx.vertex_array(program, content, index_buffer=index, index_element_size=4, skip_errors=True)

    def _mode(self, geometry: Geometry, kind: str) -> int:
        ctx = self.ctx
        if kind == "points" or geometry.mode == "points":
            return ctx.POINTS
        if geometry.mode == "lines":
            return ctx.LINES
        return ctx.TRIANGLES

    def _features(self, state: DrawState, rows: np.ndarray, uniform: bool) -> tuple:
        """Program features of a draw: the state's plus light count and, when shared, the material model."""
        features = state.features
        if state.kind in ("mesh", "points"):
            features = features + (("LIGHTS", self._lights_for(state.switch).types),)
            if self._camera_used is not None and self._camera_used.is_orthographic:
                features = features + (("ORTHO", True),)
            if uniform:
                features = features + (("MODEL", int(round(float(rows[0, 27])))), ("UNIFORM_MATERIAL", True))
                if rows[0, 35] > 0.0:
                    features = features + (("HIGHLIGHT", True),)
        return features

    def _set_material(self, prog: Any, row: np.ndarray) -> None:
        for name, lo in (("u_spec", 20), ("u_emis", 24), ("u_amb", 28), ("u_hl", 32), ("u_extra", 36)):
            u = prog.get(name, None)
            if u is not None:
                u.write(row[lo : lo + 4].tobytes())

    def _draw_batch(self, batch: Batch) -> int:
        state = batch.state
        drawer = self._drawers.get(state.kind)
        if drawer is not None:
            return drawer(self, batch.items, state)
        n = len(batch.items)
        features = self._features(state, batch.rows, batch.uniform)
        single = n == 1 and batch.uniform and state.kind == "mesh"
        if single:
            # one instance: model matrix and colour as uniforms, like a hand-written draw call
            features = features + (("SINGLE", True),)
        prog = self.programs.get(state.kind, features)
        stride = 0 if single else 20 if batch.uniform else ROW
        if batch.geometry.buffers is None or batch.stride != stride or (stride and batch.capacity < n):
            if batch.vao is not None:
                batch.vao.release()
                batch.vao = None
            if batch.buffer is not None:
                batch.buffer.release()
                batch.buffer = None
            capacity = max(n, 1)
            if stride:
                batch.buffer = gpu_call(
                    self.ctx.buffer, reserve=capacity * stride * 4, dynamic=True, what="instance data"
                )
            batch.capacity = capacity
            batch.stride = stride
            batch.dirty = (0, n)
        if batch.vao is None or batch.program is not prog:
            if batch.vao is not None:
                batch.vao.release()
            batch.program = prog
            batch.vao = self._vao(batch.geometry, prog, batch.buffer, state.kind, compact=stride == 20)
        if batch.dirty is not None:
            if stride:
                lo, hi = batch.dirty
                data = batch.rows[lo:hi] if stride == ROW else np.ascontiguousarray(batch.rows[lo:hi, :20])
                batch.buffer.write(data.tobytes(), offset=lo * stride * 4)
            batch.dirty = None
        if single:
            row = batch.rows[0]
            prog["i_model"].write(row[:16].tobytes())
            u = prog.get("i_color", None)
            if u is not None:
                u.write(row[16:20].tobytes())
        self._apply_state(state)
        self._set_uniforms(prog, state)
        if batch.uniform:
            self._set_material(prog, batch.rows[0])
        batch.vao.render(self._mode(batch.geometry, state.kind), instances=n)
        return 1

    def _draw_others(self, items: list[DrawItem]) -> int:
        """Transparent items back to front (blending on, depth writes off), then overlays."""
        transparent = [it for it in items if it.transparent and not it.state.overlay]
        overlays = [it for it in items if it.state.overlay]
        calls = 0
        if transparent:
            rows = np.stack([it.row for it in transparent])
            centers = np.array([(it.geometry.bounds[0] + it.geometry.bounds[1]) / 2.0 for it in transparent])
            mats = rows[:, :16].reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
            world = np.einsum("nij,nj->ni", mats[:, :3, :3], centers) + mats[:, :3, 3]
            z = world @ self._view[2, :3] + self._view[2, 3]
            order = np.argsort(z, kind="stable")  # most negative z (farthest) first
            runs: list[tuple[Any, DrawState, list[int]]] = []
            for i in order:
                it = transparent[i]
                if runs and runs[-1][0] is it.geometry and runs[-1][1] is it.state:
                    runs[-1][2].append(i)
                else:
                    runs.append((it.geometry, it.state, [i]))
            default_blend = ("src_alpha", "one_minus_src_alpha", "add")
            for geometry, state, indices in runs:
                drawer = self._drawers.get(state.kind)
                if drawer is not None:
                    calls += drawer(self, [transparent[i] for i in indices], state)
                    continue
                data = rows[indices]
                uniform = uniform_material(data)
                buf, vao, prog = self._transient_vao(
                    geometry, state, len(indices), self._features(state, data, uniform)
                )
                buf.write(data.tobytes())
                if uniform:
                    self._set_material(prog, data[0])
                self._apply_state(state, blend_override=state.blend or default_blend, depth_mask=False)
                self._set_uniforms(prog, state)
                mode = self._mode(geometry, state.kind)
                if state.cull == "none" and geometry.mode == "triangles" and state.kind == "mesh":
                    # back faces first, then front faces: closed transparent shapes blend correctly
                    for face in ("front", "back"):
                        self._gl_state["cull_override"] = face
                        self._apply_state(state, blend_override=state.blend or default_blend, depth_mask=False)
                        vao.render(mode, instances=len(indices))
                        calls += 1
                    self._gl_state["cull_override"] = None
                else:
                    vao.render(mode, instances=len(indices))
                    calls += 1
        for it in overlays:
            drawer = self._drawers.get(it.state.kind)
            if drawer is not None:
                calls += drawer(self, [it], it.state)
        return calls

    def _transient_vao(self, geometry: Geometry, state: DrawState, n: int, features: tuple) -> tuple[Any, Any, Any]:
        prog = self.programs.get(state.kind, features)
        key = (id(geometry), id(state), id(prog))
        entry = self._transient.get(key)
        if entry is not None and entry[2] >= n and geometry.buffers is not None:
            return entry[0], entry[1], prog
        if entry is not None:
            entry[1].release()
            entry[0].release()
        capacity = max(n, 4)
        buf = gpu_call(self.ctx.buffer, reserve=capacity * ROW * 4, dynamic=True, what="instance data")
        vao = self._vao(geometry, prog, buf, state.kind)
        self._transient[key] = (buf, vao, capacity)
        return buf, vao, prog

    # -- read back -------------------------------------------------------------
    def read(self, read_depth: bool = True) -> Image:
        """Resolve multisampling and read the image (colour, and eye-space depth unless ``read_depth=False``)."""
        with self.current():
            return self._read(read_depth)

    def _read(self, read_depth: bool) -> Image:
        t = self._targets
        drawn = self.framebuffer
        if self._target_stack:
            fbo = drawn
        else:
            if drawn is not t["fbo"]:
                self.ctx.copy_framebuffer(t["fbo"], drawn)
            fbo = t["fbo"]
        w, h = self._size
        data = fbo.read(components=4, alignment=1)
        array = np.frombuffer(data, np.uint8).reshape(h, w, 4)[::-1]
        depth = None
        if read_depth:
            raw = np.frombuffer(fbo.read(components=1, attachment=-1, dtype="f4", alignment=1), np.float32).reshape(
                h, w
            )[::-1]
            depth = self.linear_depth(raw)
        return Image(np.ascontiguousarray(array), depth, engine="gl", info=dict(self.stats))

    def linear_depth(self, raw: np.ndarray) -> np.ndarray:
        """Window depth in [0, 1] -> eye-space distance along the view axis (inf for the far plane)."""
        camera = self._camera_used
        if camera is None:
            camera = self._camera_matrices()[0]
        n, f = camera.near, camera.far
        d = raw.astype(np.float64)
        if camera.is_orthographic:
            z = n + d * (f - n)
        else:
            ndc = 2.0 * d - 1.0
            with np.errstate(divide="ignore", invalid="ignore"):
                z = 2.0 * f * n / ((f + n) - ndc * (f - n))
        out = z.astype(np.float32)
        out[raw >= 1.0] = np.inf
        return out

    # -- resources ---------------------------------------------------------------
    def live_buffers(self) -> int:
        """GPU buffers this engine holds now (geometry, instance data, transient), for leak checks."""
        n = sum(len(g.buffers) for g in self._uploaded() if g.buffers is not None)
        n += sum(1 for b in self._batches.values() if b.buffer is not None)
        n += sum(1 for k, v in self._transient.items())
        return n

    def release(self) -> None:
        """Free every GPU resource (and the context when the engine created it)."""
        with self.current():
            self._release()
        if self._own_context:
            self.ctx.release()

    def _release(self) -> None:
        for batch in self._batches.values():
            batch.release()
        self._batches.clear()
        self._batch_order = []
        for buf, vao, _ in self._transient.values():
            vao.release()
            buf.release()
        self._transient.clear()
        for g in self._uploaded():
            g.release()
        for entry in self.__dict__.get("_textures", {}).values():
            entry[2].release()
        self.programs.release()
        seen = set()
        for obj in self._targets.values():
            if id(obj) not in seen:
                seen.add(id(obj))
                obj.release()
        self._targets.clear()
        self._list = []
        self._node_cache.clear()
        self._compiled = None

    def __enter__(self) -> GLEngine:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.release()


def _factor(ctx: Any, name: str) -> int:
    return getattr(ctx, name.upper())


def _equation(ctx: Any, name: str) -> int:
    return {
        "add": ctx.FUNC_ADD,
        "subtract": ctx.FUNC_SUBTRACT,
        "reverse_subtract": ctx.FUNC_REVERSE_SUBTRACT,
        "min": ctx.MIN,
        "max": ctx.MAX,
    }[name]
