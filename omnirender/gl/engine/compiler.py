"""Compiling a scene into draw items (the GL engine's one traversal, through the core interpreter).

The GL engine evaluates the scene with the core's interpreter
(:meth:`~omnirender.core.engine.Engine.run`), on *local* node programs whose
child nodes are ``NODE`` ops, and hooks in where it needs to:

* :meth:`eval_node` caches the draw items of every node occurrence: a node
  whose version did not move, entered in an unchanged state, is replayed from
  the cache without traversal, so a frame where one child of a 10,000-child
  node changed recompiles only that child;
* :meth:`run_technique` opens a nested :class:`~.drawlist.Scope` for a
  technique and compiles what it scopes *once*; its passes run at draw time,
  every frame (:mod:`.frame`);
* ``on_enter`` / ``on_leave`` keep the group tags of the current path, which
  pass masks test.

Painters append draw items through :meth:`submit`; nothing here calls OpenGL.
The active GL state attributes are captured declaratively (:mod:`.state`),
materials into the named instance row (:mod:`.layout`).  Lights, camera and
background come from the core's cached pre-evaluation.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...attributes import Background, BumpMap, DrawStyle, Fog, Highlight, MultiTexture, Texture
from ...attributes.photometry import linear_rgb
from ...attributes.surface import Appearance, appearance_key, resolve_appearance
from ...core.component import RenderingComponent
from ...core.light import LightSwitch
from ...core.transform import Transform
from ...scene.node import Node
from ..deferred.models import MaterialDescription
from .attributes import CullFace, GLState
from .drawlist import DrawItem, DrawState, Scope
from .geometry import Geometry
from .instancing import instance_rows
from .layout import PBR, PHONG, ROW
from .shaders import LAYER_BLENDS
from .state import FillMode, LineWidth, defaults, kinds

__all__ = ["DrawListCompiler", "TextureSet", "linear_rgb"]

_DEFAULT_POINT_SIZE = float(DrawStyle().point_size)  # without a DrawStyle, points get its default size
_MODEL = ROW.slice("model")
_COLOR = ROW.slice("color")
_SHADING_MODEL = ROW.at("emission", "model")
_MATERIAL_ID = ROW.at("pbr", "material")
_HIGHLIGHT_ON = ROW.at("highlight", "on")
_POINT_SIZE = ROW.at("point", "size")
FOG_MODES = {"linear": 0.0, "exp": 1.0, "exp2": 2.0}


def _uv_matrix(texture: Any) -> tuple[float, ...]:
    """A texture's coordinate transform as a GLSL mat3 (column-major)."""
    return tuple(float(x) for x in texture.uv_matrix().T.ravel())


class TextureSet:
    """What an appearance needs from the GL state: textures to bind, program features, uniforms.

    ``textures`` are (sampler uniform, om.Texture, sRGB) triples; ``features``
    and ``uniforms`` apply where the shape has texture coordinates, ``alpha``
    and ``alpha_uniforms`` (cut-out, opaque alpha) everywhere.
    """

    __slots__ = ("textures", "features", "uniforms", "uv1", "normal", "alpha", "alpha_uniforms", "base")

    def __init__(self, app: Appearance) -> None:
        textures: list[tuple[str, Any, bool]] = []
        features: list[tuple[str, Any]] = []
        uniforms: list[tuple[str, Any]] = []

        def slot(feature: str, sampler: str, suffix: str, texture: Any, srgb: bool) -> None:
            textures.append((sampler, texture, srgb))
            if feature:
                features.append((feature, True))
            features.append((f"UVSET_{suffix.upper()}", int(texture.uv_set)))
            uniforms.append((f"u_uvm_{suffix}", _uv_matrix(texture)))

        self.base = app.texture
        if app.texture is not None:
            slot("TEXTURE", "u_texture", "base", app.texture, True)
        if app.layers:
            features.append(("LAYERS", len(app.layers)))
            for i, layer in enumerate(app.layers):
                slot("", f"u_layer{i}", f"layer{i}", layer.texture, True)
                features.append((f"LAYER_BLEND{i}", LAYER_BLENDS[layer.blend]))
                uniforms.append((f"u_layer_opacity{i}", float(layer.opacity)))
        normal, scale = app.normal_map()
        self.normal = normal is not None
        if normal is not None:
            slot("", "u_normal_texture", "normal", normal, False)
            uniforms.append(("u_normal_scale", float(scale)))
        if app.model == "pbr":
            if app.metallic_roughness_texture is not None:
                slot("MR_TEXTURE", "u_mr_texture", "mr", app.metallic_roughness_texture, False)
            if app.occlusion_texture is not None:
                slot("OCCLUSION_TEXTURE", "u_occlusion_texture", "occlusion", app.occlusion_texture, False)
                uniforms.append(("u_occlusion_strength", float(app.occlusion_strength)))
            if app.emissive_texture is not None:
                slot("EMISSIVE_TEXTURE", "u_emissive_texture", "emissive", app.emissive_texture, True)
        self.textures = tuple(textures)
        self.features = tuple(features)
        self.uniforms = tuple(uniforms)
        self.uv1 = any(t.uv_set == 1 for _, t, _ in textures)
        if app.alpha_mode == "mask":
            self.alpha: tuple[tuple[str, Any], ...] = (("ALPHA_MASK", True),)
            self.alpha_uniforms: tuple[tuple[str, Any], ...] = (("u_alpha_cutoff", float(app.alpha_cutoff)),)
        elif app.model == "pbr" and app.alpha_mode == "opaque":
            self.alpha, self.alpha_uniforms = (("ALPHA_OPAQUE", True),), ()
        else:
            self.alpha, self.alpha_uniforms = (), ()


class _NodeEntry:
    """A node occurrence's contributions (items and scopes), valid while its version and own components hold."""

    __slots__ = ("ref", "version", "own", "entries")

    def __init__(self, node: Any, own: tuple, entries: list[Any]) -> None:
        self.ref = weakref.ref(node)
        self.version = node.version
        self.own = own
        self.entries = entries


class DrawListCompiler:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: the compile traversal's hooks, state capture, ``submit``."""

    # -- the interpreter's hooks --------------------------------------------------
    def on_enter(self, node: Any) -> None:
        groups = node.groups
        stack = self._group_path
        stack.append(stack[-1] + (groups,) if groups else stack[-1])

    def on_leave(self, node: Any) -> None:
        self._group_path.pop()

    def eval_node(self, node: Any) -> Any:
        """A child node: replayed from the per-occurrence cache when unchanged, else its local program.

        Occurrences are keyed by small integers (parent occurrence, ordinal),
        so keys stay flat in graphs of any depth.
        """
        frames = self._compile_frames
        if frames:
            parent = frames[-1]
            parent[1] += 1
            pair = (parent[0], parent[1])
            key = self._occurrences.get(pair)
            if key is None:
                self._next_occurrence += 1
                key = self._occurrences[pair] = self._next_occurrence
            entry = self._node_cache.get(key)
            # an entry exists only for a node the (unchanged) mask admitted: the hit needs no mask test
            if entry is not None and not parent[2] and entry.ref() is node and entry.version == node.version:
                self._scope.entries.extend(entry.entries)
                return None
        groups = node.groups
        if groups and not self.admits(groups):
            return None
        local = getattr(node, "local_program", None)
        if local is None or not frames:  # a viewer snapshot, or immediate mode: nothing to cache
            return node.program(), None
        scope = self._scope
        same = entry is not None and entry.ref() is node
        own = tuple([x if isinstance(x, Node) else (x, x.version) for x in node.items])
        frames.append([key, 0, parent[2] or not same or entry.own != own])
        start = len(scope.entries)

        def store() -> None:
            frames.pop()
            self._node_cache[key] = _NodeEntry(node, own, scope.entries[start:])

        return local(), store

    def run_technique(self, technique: Any, program: list[tuple[int, Any]]) -> None:
        """A technique's scope: compiled once into a nested Scope; its passes run when the frame is drawn."""
        if not technique.supported(self):
            self.run_program(program)  # ignored: what it scopes is evaluated once, as if it were not there
            return
        scope = Scope(technique)
        outer = self._scope
        outer.entries.append(scope)
        self._scope = scope
        previous = self.technique
        self.technique = technique  # its service and handler overrides apply to what it scopes
        path = self._technique_path
        self._technique_path = (*path, technique)
        try:
            self.run_program(program)
        finally:
            self.technique = previous
            self._scope = outer
            self._technique_path = path

    def begin(self, root: Any) -> None:
        """The core's pre-evaluation; a following ``render(None)`` uses its camera and lights (the viewer's way)."""
        super().begin(root)  # type: ignore[misc]
        self._preevaluated = True
        self._state_dirty = True
        self._surface_dirty = True

    # -- compile ---------------------------------------------------------------------
    def compile(self, scene: Any, mask: Any = None) -> Scope:
        """Compile ``scene`` (a Node or components) into the root scope; cached while nothing changed."""
        if mask is not None:
            self.mask = mask
        if not hasattr(scene, "local_program"):
            scene = Node.transient([scene] if isinstance(scene, RenderingComponent) else scene)
        mask_key = self._mask
        c = self._compiled
        changed = self._journal.drain()
        if len(kinds()) != self._kinds_seen:
            self._new_state_kinds()
            c = None
        if c is not None and c[0]() is scene and c[2] == mask_key:
            if c[1] == scene.version:
                self.stats["compiled"] = False
                return self._root
            if c[3] == scene.structure_version:
                # only transforms moved or instance arrays changed: rewrite those rows, no traversal (dynamic.py)
                count = self._apply_changes(changed)
                if count is not None:
                    self.stats["incremental"] = count
                    self._refresh_declarations(scene)
                    self._compiled = (c[0], scene.version, mask_key, c[3])
                    self.stats["compiled"] = False
                    return self._root
        self.sync_registry()
        camera = scene.declarations(self.mask_function).camera
        full_key = (mask_key, camera[0].mask if camera is not None else None)
        if c is None or c[0]() is not scene or c[2] != mask_key or self._full_key != full_key:
            self._node_cache.clear()
            self._occurrences.clear()
        self._full_key = full_key
        root = Scope(None)
        self._scope = root
        self._compile_frames = [[0, 0, False]]
        generation = self.material_table.generation
        try:
            self.run(scene)
            if self.material_table.generation != generation:  # the material table started again: every id anew
                self._node_cache.clear()
                self._surface_memo.clear()
                self._state_dirty = self._surface_dirty = True
                root = self._scope = Scope(None)
                self._compile_frames = [[0, 0, False]]
                self.run(scene)
        except BaseException:
            self._surface.clear()
            self._clips.clear()
            self._node_cache.clear()
            self._compiled = None
            raise
        finally:
            self._compile_frames = []
            self._scope = self._immediate
        self._compiled = (weakref.ref(scene), scene.version, mask_key, scene.structure_version)
        self._prune_caches()
        self._install(root)
        self._move_plan = None
        self.stats["compiled"] = True
        return root

    def _new_state_kinds(self) -> None:
        """A GL state class was defined since the last compile: items must capture one more value."""
        self._kinds_seen = len(kinds())
        self._defaults = defaults()
        self._states.clear()
        self._node_cache.clear()
        self._compiled = None
        self._state_dirty = True

    def _prune_caches(self) -> None:
        """Drop cache entries of nodes that no longer exist (amortised: when the cache doubled)."""
        if len(self._node_cache) > self._prune_limit:
            self._node_cache = {k: v for k, v in self._node_cache.items() if v.ref() is not None}
            live = set(self._node_cache)
            self._occurrences = {pair: k for pair, k in self._occurrences.items() if k in live}
            self._prune_limit = max(4096, 2 * len(self._node_cache))

    # -- what painters call ------------------------------------------------------------
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
        if self._state_dirty or len(self._state_base[0]) != self._kinds_seen:
            if len(kinds()) != self._kinds_seen:
                self._new_state_kinds()
            self._resolve_state()
        if self._surface_dirty:
            self._resolve_surface()
        m = self.model_matrix()
        if local is not None:
            m = m @ local
        row = self._surface_row.copy()
        row[_MODEL] = m.T.ravel()
        if kind is None:
            kind = (
                "points"
                if geometry.mode == "triangles" and self._fill == "points"
                else ("mesh" if geometry.mode == "triangles" else geometry.mode)
            )
        app = self._appearance
        if transparent is None:
            see_through = app.alpha_mode == "blend" or (
                app.alpha_mode == "opaque" and app.model == "phong" and geometry.translucent
            )
            transparent = self._blend_on or (see_through and not self._alpha_tested)
        cull = None
        single = not app.double_sided and kind == "mesh"
        if (single or (geometry.closed and not transparent)) and kind == "mesh" and self._auto_cull:
            # a closed opaque surface never shows its back faces, a single-sided material hides them: cull them
            # (mirrored instances: the front)
            cull = "back" if np.linalg.det(m[:3, :3]) > 0.0 else "front"
        state = self._state_for(kind, geometry, extra, cull, int(row[_SHADING_MODEL]))
        item = DrawItem(
            geometry,
            state,
            row,
            transparent,
            self.current_node,
            self._group_path[-1],
            tuple(self.context.mono_stack(Transform)),
            local,
            self._technique_path,
        )
        self._scope.entries.append(item)
        return item

    def capture(self, shape: Any) -> list[DrawItem]:
        """The draw items ``shape`` makes in the current state, without drawing them (instance sets use it)."""
        scope = Scope()
        outer = self._scope
        self._scope = scope
        try:
            self.eval(shape)
        finally:
            self._scope = outer
        return scope.all_items()

    def submit_instances(
        self, source: Any, template: DrawItem, matrices: np.ndarray, colors: np.ndarray | None, may_mirror: bool
    ) -> DrawItem:
        """An item drawing ``template`` once per matrix (``(N, 4, 4)``, after the current model matrix).

        ``source`` is the instance set; ``colors`` (``(N, 4)`` display RGBA or
        None) replace the template's colour as ``om.Color`` would.  The rows
        are made with numpy in one go (:func:`~.instancing.instance_rows`);
        the item is drawn as one instanced batch.
        """
        made = instance_rows(
            template.row, template.local, template.transparent, self.model_matrix(), matrices, colors, may_mirror
        )
        item = DrawItem(
            template.geometry,
            self.instance_state(template, made.mirrored),
            template.row,
            made.transparent,
            template.node,
            template.groups,
            template.chain,
            None,
            template.techniques,
        )
        item.instances = made.rows
        item.instance_models = made.models
        item.source = source
        item.template = template
        self._scope.entries.append(item)
        return item

    def instance_state(self, template: DrawItem, mirrored: bool) -> DrawState:
        """The template's state, or the same without face culling when some instance mirrors."""
        state = template.state
        if mirrored and not template.transparent and state.value(CullFace) in ("back", "front"):
            # mirrored instances: cull nothing rather than the wrong faces of some
            state = self._state_for(
                state.kind, template.geometry, state.extra, "none", int(template.row[_SHADING_MODEL])
            )
        return state

    def _resolve_state(self) -> None:
        mono = self.mono
        style = mono(DrawStyle)
        self._fill = style.mode if style is not None else "filled"
        # without a DrawStyle: DrawStyle's default (1 px), as in POV-Ray and Mitsuba
        self._point_size = float(style.point_size) if style is not None else _DEFAULT_POINT_SIZE
        values = []
        features: list[tuple[str, Any]] = []
        uniforms: list[tuple[str, Any]] = []
        code: list[Any] = []
        special = False
        cull_set = False
        for k in kinds():
            if issubclass(k, GLState):
                top = mono(k)
                value = top.capture() if top is not None else k.default
                if k is CullFace:
                    cull_set = top is not None
                    if top is None and style is not None:
                        value = style.cull
            elif k is FillMode:
                value = self._fill == "wireframe"
            elif k is LineWidth:
                value = float(style.line_width) if style is not None else 1.0
            elif k.source() is not None:  # a kind capturing a generic attribute (Shadowing, Mirror)
                top = mono(k.source())
                value = k.default if top is None else k.from_attribute(top)
            else:
                value = k.default
            values.append(value)
            if value != k.default:
                special = special or k.orders(value)
                extra = k.features(value)
                if extra:
                    features.extend(extra)
                    uniforms.extend(k.uniforms(value))
                    if k.fragment_code or k.fragment_main:
                        code.append(k)
        raster = tuple(values)
        from .attributes import AlphaTest, Blend

        self._blend_on = raster[Blend.index] is not None
        # an om.gl.AlphaTest cuts out what the alpha hides: such surfaces are drawn (and write depth) as opaque ones
        self._alpha_tested = raster[AlphaTest.index] is not None
        cull_value = raster[CullFace.index]
        # automatic back-face culling only where nothing decides culling and nothing shows the inside
        self._auto_cull = not cull_set and cull_value == "none" and not self._clips and self._fill != "wireframe"
        fog = mono(Fog)
        fog_key = None
        if fog is not None:
            fog_key = (
                linear_rgb(fog.color),
                float(fog.start),
                float(fog.end),
                float(fog.density),
                FOG_MODES[fog.mode],
            )
        self._state_base = (
            raster,
            tuple(features),
            tuple(uniforms),
            tuple(code),
            special,
            tuple(plane for _, plane in self._clips),
            fog_key,
            mono(LightSwitch),
            style is not None and style.shading == "flat",
        )
        self._state_dirty = False

    def _check_texture(self, texture: Any) -> None:
        if getattr(texture, "rendered", False):
            return  # a render texture: its pipeline checks its size when it is made
        checked = self._checked_textures.get(id(texture))
        if checked is not None and checked[0]() is texture and checked[1] == texture.version:
            return
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
        self._checked_textures[id(texture)] = (weakref.ref(texture), texture.version)

    def _state_for(self, kind: str, geometry: Geometry, extra: Any, cull_override: str | None, model: int) -> DrawState:
        raster, state_features, uniforms, code, special, clip, fog, switch, flat = self._state_base
        texset = self._texset
        features: list[tuple[str, Any]] = []
        if geometry.colors is not None:
            features.append(("VCOLOR", True))
        textured = bool(texset.textures) and geometry.texcoords is not None and kind == "mesh"
        bound: tuple = ()
        if textured:
            features.append(("UVS", True))
            features.extend(texset.features)
            if texset.uv1 and geometry.texcoords1 is not None:
                features.append(("UV1", True))
            if texset.normal and geometry.tangent_source is not None:
                features.append(("NORMAL_MAP", True))
            uniforms = uniforms + texset.uniforms
            bound = texset.textures
        if kind in ("mesh", "points") and texset.alpha:
            features.extend(texset.alpha)
            uniforms = uniforms + texset.alpha_uniforms
        if flat and kind == "mesh":
            features.append(("FLAT", True))
        if clip:
            features.append(("NCLIP", len(clip)))
        if fog is not None:
            features.append(("FOG", True))
        if kind == "points" and geometry.sizes is not None:
            features.append(("VSIZE", True))
        if kind in ("mesh", "points"):
            features.append(("MODEL", model))
            features.extend(state_features)
        if geometry.program_features:  # geometry drawn by a program of its own (GPU-tessellated NURBS patches)
            features.extend(geometry.program_features)
            uniforms = uniforms + geometry.program_uniforms
        if cull_override is not None:
            raster = raster[: CullFace.index] + (cull_override,) + raster[CullFace.index + 1 :]
        key = (kind, tuple(features), extra, raster, bound, clip, fog, switch, uniforms, code)
        state = self._states.get(key)
        if state is None:
            if len(self._states) > 4096:  # e.g. text labels that change every frame
                self._states.clear()
            state = self._states[key] = DrawState(
                kind,
                tuple(features),
                raster,
                uniforms=uniforms if kind in ("mesh", "points") else (),
                code=code if kind in ("mesh", "points") else (),
                texture=texset.base if textured else None,
                textures=bound,
                clip=clip,
                fog=fog,
                switch=switch,
                extra=extra,
                overlay=kind == "text",
                special=special,
            )
        return state

    def _resolve_surface(self) -> None:
        """The one appearance model (``resolve_appearance``) as an instance row and a texture set."""
        mono = self.mono
        texture, layers, bump = mono(Texture), mono(MultiTexture), mono(BumpMap)
        highlight = mono(Highlight)
        description = mono(MaterialDescription)
        key = (
            appearance_key(self._surface, texture, layers, bump),
            None if highlight is None else (id(highlight), highlight.version),
            None if description is None else (id(description), description.version),
        )
        memo = self._surface_memo
        entry = memo.get(key)
        if entry is None:
            app = resolve_appearance(self._surface, texture, layers, bump)
            for tex in app.textures:
                self._check_texture(tex)
            # the attributes are kept alive with the entry, so the ids in its key stay theirs
            row = self._material_row(app, highlight)
            # the shading model and the id of the material description (the deferred pipeline's material table)
            if description is not None:
                row[_SHADING_MODEL] = description.model.number
            row[_MATERIAL_ID] = self.material_table.for_appearance(app, description)
            entry = (app, row, TextureSet(app), (texture, layers, bump, highlight, description))
            if len(memo) > 256:
                memo.clear()
            memo[key] = entry
        app, row, texset, _ = entry
        point_size = self._point_size
        if row[_POINT_SIZE] != point_size:
            row = row.copy()
            row[_POINT_SIZE] = point_size
        self._appearance = app
        self._texset = texset
        self._surface_row = row
        self._surface_dirty = False

    def _material_row(self, app: Appearance, highlight: Any) -> np.ndarray:
        """A row holding the surface fields (the model matrix is filled per item); colours are linear."""
        row = np.zeros(ROW.stride, np.float32)
        alpha = 1.0 if app.model == "pbr" and app.alpha_mode != "blend" else app.alpha
        row[_COLOR] = (*app.base, alpha)
        if app.model == "pbr":
            row[ROW.slice("emission")] = (*app.emission, PBR)
            row[ROW.slice("pbr")] = (app.roughness, app.metallic, 0.0, 0.0)
        else:
            row[ROW.slice("specular")] = (*app.specular, app.shininess)
            row[ROW.slice("emission")] = (*app.emission, PHONG)
            row[ROW.slice("ambient")] = (*app.ambient, 1.0 if app.ambient_follows_base else 0.0)
        if highlight is not None:
            row[ROW.slice("highlight")] = (*linear_rgb(highlight.color), 1.0)
        row[_POINT_SIZE] = _DEFAULT_POINT_SIZE
        return row

    # -- queries ----------------------------------------------------------------------
    @property
    def scene_background(self) -> Any:
        """The first ``om.Background`` of the last pre-evaluated scene, or None."""
        declared = self.declared
        if declared is None:
            return None
        found = declared.first(Background)
        return None if found is None else found[0]

    @property
    def scene_lights(self) -> list[tuple[Any, np.ndarray]]:
        """The lights of the last pre-evaluated scene with their world matrices."""
        return [] if self.declared is None else self.declared.lights
