"""Drawing the items of a scope in one (composed) pass: instanced batches, sorted transparency, overlays, read-back.

Opaque items are grouped into batches per scope segment (one instanced call
per geometry and state; only changed instance rows are uploaded, and only the
fields the batch's program variants read).  Transparent items are sorted back
to front each time they are drawn, with blending on and depth writes off;
closed transparent shapes draw back faces, then front faces.  Overlays (text)
come last.  What a pass changes (state overrides, shader features, camera) is
applied per draw from the :class:`~.passes.Composed` pass.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...core.mask import compile_mask
from ...image import Image
from ..techniques.shadows import ATLAS, SHADOW_UNIT
from .attributes import Blend, CullFace, DepthMask
from .drawlist import Batch, DrawItem, DrawState, Scope, Segment, plan_batches, uniform_material
from .geometry import Geometry
from .layout import ROW
from .lighting import LightUniforms
from .passes import Composed
from .pipelines import apply_sampling
from .resources import gpu_call
from .shaders import instance_fields
from .state import LineWidth, ShadowingState

__all__ = ["BatchRenderer", "SORT_MIN"]

_GL_CLIP_DISTANCE0 = 0x3000
#: First texture unit of a pass's Shader inputs (after the shadow atlas; units below are the materials').
PASS_INPUT_UNIT = SHADOW_UNIT + 1
#: Batches with at least this many opaque instances are drawn front to back (re-sorted when the view changes).
SORT_MIN = 64
_TRANSLATION = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)
_MODEL = ROW.slice("model")
_HIGHLIGHT_ON = ROW.at("highlight", "on")
_OVER = ("src_alpha", "one_minus_src_alpha", "add")
_MATERIAL_UNIFORMS = (("u_spec", "specular"), ("u_emis", "emission"), ("u_amb", "ambient"), ("u_pbr", "pbr"),
                      ("u_hl", "highlight"), ("u_point", "point"))  # fmt: skip


class BatchRenderer:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: install the compiled scopes, draw them, read back."""

    # -- installing a compiled root scope ------------------------------------------------
    def _install(self, root: Scope) -> None:
        """Make ``root`` the draw list: rewrite changed rows in place when the structure is the same, else re-plan."""
        old = self._root
        self._bounds = None
        self._caster_bounds = None
        self._mirrors = None
        self.draw_list_version += 1
        if old is not None and old is not root and old.entries and _same_shape(old, root):
            self.stats["incremental"] = self._update_in_place(old, root)
            return
        self.stats["incremental"] = None
        pool = self._batch_pool
        self._batch_pool = {}
        self._plan(root, (), pool)
        for batch in pool.values():
            batch.release()
        if old is not None and old is not root:
            for scope in old.walk():
                _release_filtered(scope)
        self._root = root
        self._item_count = len(root.all_items())
        self._sweep(root)

    def _plan(self, scope: Scope, where: tuple, pool: dict[tuple, Batch]) -> None:
        parts: list[Segment | Scope] = []
        run: list[DrawItem] = []

        def flush() -> None:
            if run:
                parts.append(self._segment(list(run), (*where, len(parts)), pool))
                run.clear()

        for entry in scope.entries:
            if isinstance(entry, Scope):
                flush()
                self._plan(entry, (*where, len(parts)), pool)
                parts.append(entry)
            else:
                run.append(entry)
        flush()
        scope.parts = parts
        scope.positions = None
        scope.filtered = {}

    def _segment(self, items: list[DrawItem], where: tuple, pool: dict[tuple, Batch]) -> Segment:
        segment = Segment(items)
        groups, slots = plan_batches(items)
        batches: dict[tuple, Batch] = {}
        for key, group in groups.items():
            pool_key = (where, *key)
            batch = pool.pop(pool_key, None)
            if batch is None:
                batch = Batch(key[0], key[1])
            batch.items = group
            batch.rows = np.stack([it.row for it in group]) if len(group) > 1 else group[0].rows().copy()
            batch.dirty = (0, len(group))
            batch.uniform = uniform_material(batch.rows)
            batch.sorted_for = None
            batch.position = None
            batches[key] = batch
            self._batch_pool[pool_key] = batch
        segment.batches = list(batches.values())
        segment.slots = [None if s is None else (batches[s[0]], s[1]) for s in slots]
        if where and where[0] == "filtered":
            for batch in segment.batches:
                _select_from_source(batch)
        else:
            for item, slot in zip(items, segment.slots, strict=True):
                item.slot = slot
                if slot is not None and item.instances is None:
                    # the item's row becomes its batch row: a moved transform writes the row once (dynamic.py)
                    item.row = slot[0].rows[slot[1]]
        return segment

    def _update_in_place(self, old: Scope, new: Scope) -> int:
        """Copy the rows of ``new``'s items into ``old``'s structure (checked to be the same); returns the count."""
        changed = 0
        stack = [(old, new)]
        while stack:
            a, b = stack.pop()
            differ = [i for i, (x, y) in enumerate(zip(a.entries, b.entries, strict=True)) if x is not y]
            if not differ:
                continue
            where = a.positions
            if where is None:
                where = a.positions = _positions(a)
            touched = regroup = False
            for i in differ:
                x, y = a.entries[i], b.entries[i]
                if isinstance(x, Scope):
                    stack.append((x, y))  # type: ignore[arg-type]
                    continue
                a.entries[i] = y
                segment, position = where[i]
                segment.items[position] = y
                slot = segment.slots[position]
                if slot is None:
                    segment.others = [it for it in segment.items if it.transparent or it.state.overlay]
                else:
                    batch, index = slot
                    batch.items[index] = y
                    y.slot = slot
                    if y.instances is not None:  # an instance set's array: the whole batch, maybe another length
                        if len(batch.rows) != len(y.instances):
                            batch.position = None  # sorted and culled again
                        batch.rows = y.instances.copy()
                        batch.dirty = None
                        batch.changed(0, len(batch.rows))
                        batch.uniform = uniform_material(batch.rows)
                        changed += 1
                        touched = regroup = True
                        continue
                    x.row = x.row.copy()  # the replaced item keeps its values; its batch row is y's now
                    batch.rows[index] = y.row
                    y.row = batch.rows[index]
                    batch.mark(index)
                    if x.groups != y.groups:
                        regroup = True  # what pass masks and predicates select may differ: filter again
                    else:
                        _replace_in_views(a, batch, index, y)
                    if batch.uniform and not uniform_material(batch.rows[[0, index]]):
                        batch.uniform = False
                changed += 1
                touched = True
            if touched and regroup:
                _release_filtered(a)
        return changed

    def _sweep(self, root: Scope) -> None:
        """Release GPU objects the new list no longer uses (transient buffers, geometry, textures)."""
        items = root.all_items()
        used = {id(it.geometry) for it in items}
        drawn = {(id(it.geometry), id(it.state)) for it in items if it.transparent}
        for key in list(self._transient):
            if key[:2] not in drawn:
                buf, vao, *_ = self._transient.pop(key)
                vao.release()
                buf.release()
        self.geometry_cache.sweep(used)
        for geom in list(self._uploaded_set):
            if id(geom) not in used and not geom.persistent:
                geom.release()
        if self._textures:
            live = {(id(t), srgb) for it in items for _, t, srgb in it.state.textures}
            for key in [k for k in self._textures if k not in live]:
                self._textures.pop(key)[2].release()

    def upload(self, geometry: Geometry) -> None:
        """Make sure ``geometry`` has its GPU buffers (drawers call it)."""
        if geometry.buffers is None:
            geometry.upload(self.ctx)
            self._uploaded_set.add(geometry)

    # -- drawing a scope's items in a pass -----------------------------------------------
    def _draw_items(self, scope: Scope, composed: Composed, nested: Any) -> int:
        """Draw the items of ``scope`` that ``composed`` selects; ``nested(scope)`` runs a nested technique scope.

        Order: opaque batches and nested scopes as they were met, then
        transparent items back to front, then overlays.
        """
        classes = composed.classes
        calls = 0
        parts = scope.parts or []
        filtered = self._filter(scope, composed) if (composed.masks or composed.selects) else None
        if "opaque" in classes or composed.scopes:
            for index, part in enumerate(parts):
                if isinstance(part, Scope):
                    if composed.scopes is True:
                        calls += nested(part)
                    continue
                if "opaque" in classes:
                    batches = part.batches if filtered is None else filtered[index]
                    for batch in batches:
                        calls += self._draw_batch(batch, composed)
        others: list[DrawItem] | None = None
        if "transparent" in classes or "overlay" in classes:
            others = [it for part in parts if isinstance(part, Segment) for it in part.others]
            if filtered is not None:
                keep = self._accepts(composed)
                others = [it for it in others if keep(it)]
        if "transparent" in classes and others:
            calls += self._draw_transparent([it for it in others if it.transparent and not it.state.overlay], composed)
        if "overlay" in classes and others:
            for it in others:
                if it.state.overlay:
                    drawer = self._drawers.get(it.state.kind)
                    if drawer is not None:
                        made = drawer(self, [it], it.state)
                        self._applier.forget()
                        self.count(made, 1)
                        calls += made
        return calls

    def _accepts(self, composed: Composed) -> Any:
        masks = [compile_mask(m) for m in composed.masks]
        selects = composed.selects

        def keep(item: DrawItem) -> bool:
            for mask in masks:
                for groups in item.groups:
                    if not mask(groups):
                        return False
            return all(select(item) for select in selects)

        return keep

    def _filter(self, scope: Scope, composed: Composed) -> dict[int, list[Batch]]:
        """Batches of the opaque items a mask/predicate keeps, per segment index (cached until the scope changes)."""
        key = (composed.masks, composed.selects)
        cached = scope.filtered.get(key)
        if cached is not None:
            for batches in cached.values():
                for batch in batches:
                    batch.follow()  # rows moved or changed in place since: copied again, nothing re-planned
            return cached
        keep = self._accepts(composed)
        out: dict[int, list[Batch]] = {}
        for index, part in enumerate(scope.parts or []):
            if isinstance(part, Segment):
                kept = [it for it in part.items if keep(it)]
                out[index] = self._segment(kept, ("filtered", id(scope), key, index), {}).batches if kept else []
        scope.filtered[key] = out
        return out

    # -- batches -----------------------------------------------------------------------
    def _features(self, state: DrawState, uniform: bool, highlight: bool, composed: Composed, single: bool) -> tuple:
        """Program features of a draw: the state's, the lights, the material sharing, the pass's shading."""
        features = state.features
        shading = composed.shading()
        if state.kind in ("mesh", "points"):
            lit = not any(name in ("DEPTH_ONLY", "FLAT_COLOR", "UNLIT") for name, _ in shading)
            if lit:
                if not any(name == "PASS_SURFACE" for name, _ in shading):  # a surface pass lights nothing itself
                    features = features + (("LIGHTS", self._lights_for(state.switch).types),)
                plan = self._shadow_plan
                if plan is not None and state.raster[ShadowingState.index][1]:
                    if not any(name == "SHADOWS_OFF" for name, _ in shading):
                        features = features + plan.features()
            if self._ortho:
                features = features + (("ORTHO", True),)
            if not uniform:
                features = features + (("INSTANCE_MATERIAL", True),)
            elif single:
                features = features + (("SINGLE", True),)
        if highlight:
            features = features + (("HIGHLIGHT", True),)
        if self._linear_output:
            features = features + (("LINEAR_OUTPUT", True),)
        return features + shading

    def _draw_batch(self, batch: Batch, composed: Composed) -> int:
        state = batch.state
        drawer = self._drawers.get(state.kind)
        if drawer is not None:
            calls = drawer(self, batch.items, state)
            self._applier.forget()
            self.count(calls, len(batch.items))
            return calls
        n = len(batch.rows)
        if not n:
            return 0  # an instance set with no visible instance
        highlight = bool((batch.rows[:, _HIGHLIGHT_ON] > 0.0).any())
        single = n == 1 and batch.uniform and state.kind == "mesh"
        features = self._features(state, batch.uniform, highlight, composed, single)
        prog = self.programs.get(state.kind, features, state.code)
        fields = instance_fields(state.kind, dict(features))
        if fields and batch.buffer is not None and batch.layout is not None and batch.layout.names() != fields:
            batch.release()  # a variant reads other fields: re-pack
        if fields and (batch.buffer is None or batch.capacity < n or batch.geometry.buffers is None):
            batch.release()
            batch.layout = ROW.subset(fields)
            batch.buffer = gpu_call(
                self.ctx.buffer, reserve=max(n, 1) * batch.layout.stride * 4, dynamic=True, what="instance data"
            )
            batch.capacity = max(n, 1)
            batch.dirty = (0, n)
        volume = state.kind == "mesh" and "SHADOW_VOLUME" in dict(features)  # triangles with their neighbours
        vao = batch.vaos.get(id(prog))
        if vao is None:
            vao = batch.vaos[id(prog)] = self._vao(batch.geometry, prog, batch.buffer, state.kind, batch.layout, volume)
        if fields:
            columns = self._columns(batch.layout)
            if n >= SORT_MIN and not state.special:
                # big batches: opaque instances front to back (early depth tests skip hidden fragments) and
                # culled to the frame's view: the buffer holds the visible ones first, then the rest, so
                # passes from other cameras (shadow maps, mirrors) draw them all from the same buffer; changed
                # rows are rewritten where they lie unless culling has to be done again
                own_view = self._view_key == self._frame_view_key
                stale = batch.position is None or len(batch.position) != n
                if stale or (own_view and (batch.sorted_for != self._view_key or (batch.dirty and batch.drawn < n))):
                    visible = self._cull(batch) if own_view else None
                    z = batch.rows[:, _TRANSLATION] @ self._view[2, :3]
                    if visible is None:
                        order = np.argsort(-z, kind="stable")
                        batch.drawn = n
                    else:
                        seen, hidden = np.nonzero(visible)[0], np.nonzero(~visible)[0]
                        order = np.concatenate([seen[np.argsort(-z[seen], kind="stable")], hidden])
                        batch.drawn = len(seen)
                    batch.buffer.write(np.ascontiguousarray(batch.rows[np.ix_(order, columns)]).tobytes())
                    batch.position = np.empty(n, np.int64)
                    batch.position[order] = np.arange(n)
                    batch.sorted_for = self._view_key if own_view else None
                    batch.dirty = None
                elif batch.dirty is not None:
                    lo, hi = batch.dirty
                    where = batch.position[lo:hi]
                    first, last = int(where.min()), int(where.max()) + 1
                    order = np.empty(n, np.int64)
                    order[batch.position] = np.arange(n)
                    data = np.ascontiguousarray(batch.rows[np.ix_(order[first:last], columns)])
                    batch.buffer.write(data.tobytes(), offset=first * batch.layout.stride * 4)
                    batch.dirty = None
                if own_view:
                    n = batch.drawn
                    if not n:
                        return 0
            elif batch.dirty is not None:
                lo, hi = batch.dirty
                data = np.ascontiguousarray(batch.rows[lo:hi][:, columns])
                batch.buffer.write(data.tobytes(), offset=lo * batch.layout.stride * 4)
                batch.dirty = None
        else:
            row = batch.rows[0]
            prog["i_model"].write(row[_MODEL].tobytes())
            u = prog.get("i_color", None)
            if u is not None:
                u.write(row[ROW.slice("color")].tobytes())
        self._apply_raster(composed.raster(state.raster, self._defaults), state)
        self._set_uniforms(prog, state, composed)
        if batch.uniform:
            self._set_material(prog, batch.rows[0])
        vao.render(_TRIANGLES_ADJACENCY if volume else self._mode(batch.geometry, state.kind), instances=n)
        self.count(1, n)
        return 1

    def _cull(self, batch: Batch) -> np.ndarray | None:
        """Which instances' bounding spheres meet the view frustum (None: all of them)."""
        rows = batch.rows
        b0, b1 = batch.geometry.bounds
        center = np.append((b0 + b1) / 2.0, 1.0)
        radius = float(np.linalg.norm(b1 - b0)) / 2.0
        mt = rows[:, _MODEL].reshape(-1, 4, 4).astype(np.float64)  # each row holds M transposed
        centers = center @ mt  # (n, 4): M @ center
        scale = np.sqrt((mt[:, :3, :3] ** 2).sum(axis=2)).max(axis=1)
        clip = self._proj @ self._view
        planes = np.array([clip[3] + clip[0], clip[3] - clip[0], clip[3] + clip[1], clip[3] - clip[1],
                           clip[3] + clip[2], clip[3] - clip[2]])  # fmt: skip
        planes /= np.linalg.norm(planes[:, :3], axis=1)[:, None]
        distance = centers @ planes.T  # (n, 6) signed distances of the centres
        visible = (distance > -(radius * scale)[:, None]).all(axis=1)
        return None if visible.all() else visible

    def _columns(self, layout: Any) -> np.ndarray:
        key = layout.names()
        cols = self._column_cache.get(key)
        if cols is None:
            cols = self._column_cache[key] = layout.columns(ROW)
        return cols

    def _vao(
        self, geometry: Geometry, program: Any, buffer: Any, kind: str, layout: Any, adjacency: bool = False
    ) -> Any:
        self.upload(geometry)
        content = geometry.content(program)
        if buffer is not None and layout is not None:
            fmt, names = layout.vertex_format()
            content.append((buffer, fmt, *names))
        index = geometry.buffers.get("index") if kind != "points" else None
        if adjacency:
            index = geometry.adjacency_buffer(self.ctx)
        return self.ctx.vertex_array(program, content, index_buffer=index, index_element_size=4, skip_errors=True)

    def _mode(self, geometry: Geometry, kind: str) -> int:
        ctx = self.ctx
        if geometry.mode == "patches":  # tessellated on the GPU (gl/nurbs.py)
            ctx.patch_vertices = geometry.patch_size  # type: ignore[attr-defined]
            return ctx.PATCHES
        if kind == "points" or geometry.mode == "points":
            return ctx.POINTS
        if geometry.mode == "lines":
            return ctx.LINES
        return ctx.TRIANGLES

    def _set_material(self, prog: Any, row: np.ndarray) -> None:
        for name, field in _MATERIAL_UNIFORMS:
            u = prog.get(name, None)
            if u is not None:
                u.write(row[ROW.slice(field)].tobytes())

    def light_order(self) -> list[Any]:
        """The lights of the pass being drawn in shader order (index i is light i of the light loops)."""
        return self._lights_for(None).order

    def _lights_for(self, switch: Any) -> LightUniforms:
        key = id(switch)
        lu = self._light_cache.get(key)
        if lu is None:
            lights = self.scene_lights
            if switch is not None:
                lights = [(light, m) for light, m in lights if switch.allows(light)]
            lu = LightUniforms(lights, self._view, headlight=not self.scene_lights)
            self._light_cache[key] = lu
        return lu

    def _set_uniforms(self, prog: Any, state: DrawState, composed: Composed) -> None:
        for name, data in self._frame_uniforms.items():
            u = prog.get(name, None)
            if u is not None:
                u.write(data)
        lights = self._lights_for(state.switch)
        lights.apply(prog)
        if self._shadow_plan is not None and prog.get("u_shadow_atlas", None) is not None:
            self._shadow_plan.apply(prog, self.target(ATLAS).depth, lights.order)
        if state.clip:
            prog["u_clip"].write(np.asarray(state.clip, np.float32).tobytes())
        if state.fog is not None:
            color, start, end, density, mode = state.fog
            u = prog.get("u_fog", None)
            if u is not None:
                u.value = (start, end, density, mode)
                prog["u_fog_color"].value = color
        u = prog.get("u_viewport", None)
        if u is not None:  # lines, points and tessellated patches: half the target's size in pixels
            u.value = (self._target_size[0] / 2.0, self._target_size[1] / 2.0)
            u = prog.get("u_viewport_origin", None)
            if u is not None:  # points: the viewport's corner (a pass's viewport box)
                u.value = tuple(float(v) for v in self.ctx.viewport[:2])
        if state.kind == "lines":
            prog["u_line_width"].value = float(state.value(LineWidth))
        for unit, (sampler, texture, srgb) in enumerate(state.textures):
            u = prog.get(sampler, None)
            if u is not None:
                self._texture(texture, srgb).use(unit)
                u.value = unit
        for name, value in state.uniforms:
            u = prog.get(name, None)
            if u is not None:
                if isinstance(value, tuple) and len(value) > 4:  # arrays (NURBS trimming edges): as float32
                    u.write(np.asarray(value, np.float32)[: u.array_length * u.dimension].tobytes())
                else:
                    u.value = value
        for name, value in composed.uniforms().items():
            u = prog.get(name, None)
            if u is not None:
                if isinstance(value, tuple) and len(value) > 4:  # arrays and matrices: written as float32
                    u.write(np.asarray(value, np.float32)[: u.array_length * u.dimension].tobytes())
                else:
                    u.value = value
        inputs = composed.inputs()
        if inputs:
            for unit, (uniform, source) in enumerate(sorted(inputs.items(), key=lambda p: p[0]), start=PASS_INPUT_UNIT):
                u = prog.get(uniform, None)
                if u is not None:
                    if isinstance(source, tuple):
                        name, attachment = source
                        target = self.target(name)
                        texture = target.depth if attachment == "depth" else target.texture(attachment)
                    else:
                        texture = self._texture(source)  # an om.Texture of the pass
                    texture.use(unit)
                    u.value = unit

    def _apply_raster(self, raster: tuple, state: DrawState) -> None:
        self._applier.apply(raster)
        nclip = len(state.clip)
        if self._nclip != nclip:
            for i in range(6):
                if i < nclip:
                    self.ctx.enable_direct(_GL_CLIP_DISTANCE0 + i)
                else:
                    self.ctx.disable_direct(_GL_CLIP_DISTANCE0 + i)
            self._nclip = nclip

    def _texture(self, attr: Any, srgb: bool = True) -> Any:
        """The GL texture of an ``om.Texture``: sRGB colour data, or linear data (normal, roughness maps)."""
        if getattr(attr, "rendered", False):  # an om.gl.RenderTexture: its pipeline's last image
            return self.pipelines().texture(attr)
        key = (id(attr), srgb)
        entry = self._textures.get(key)
        if entry is not None and entry[0]() is attr and entry[1] == attr.version:
            return entry[2]
        if entry is not None:
            entry[2].release()
        img = np.ascontiguousarray(attr.image_array()[::-1])
        h, w = img.shape[:2]
        # GL_SRGB8_ALPHA8: texture images are display (sRGB) values; the GPU decodes them before filtering
        # and mipmapping, so minified and magnified textures average light, not encoded values
        internal = _GL_SRGB8_ALPHA8 if srgb else _GL_RGBA8
        tex = gpu_call(self.ctx.texture, (w, h), 4, img.tobytes(), internal_format=internal, what="a texture")
        if attr.mipmap:
            tex.build_mipmaps()
        apply_sampling(self.ctx, self.raw, tex, attr)
        self._textures[key] = (weakref.ref(attr), attr.version, tex)
        return tex

    # -- transparent items -------------------------------------------------------------
    def _draw_transparent(self, items: list[DrawItem], composed: Composed) -> int:
        """Back to front (blending on where nothing else is set, depth writes off); closed shapes back faces first."""
        if not items:
            return 0
        if any(it.instances is not None for it in items):  # an instance set's instances sort one by one
            parts = [it.rows() for it in items]
            owners = [it for it, part in zip(items, parts, strict=True) for _ in range(len(part))]
            rows = np.concatenate(parts)
            items = owners
        else:
            rows = np.stack([it.row for it in items])
        if not len(rows):
            return 0
        centers = np.array([(it.geometry.bounds[0] + it.geometry.bounds[1]) / 2.0 for it in items])
        mats = rows[:, _MODEL].reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
        world = np.einsum("nij,nj->ni", mats[:, :3, :3], centers) + mats[:, :3, 3]
        z = world @ self._view[2, :3] + self._view[2, 3]
        order = np.argsort(z, kind="stable")  # most negative z (farthest) first
        runs: list[tuple[Any, DrawState, list[int]]] = []
        for i in order:
            it = items[i]
            if (
                runs
                and runs[-1][0] is it.geometry
                and runs[-1][1] is it.state
                and not _two_faced(it.geometry, it.state)
            ):
                # instances of a two-faced run would draw all back faces, then all front faces: a nearer
                # instance's back faces would then land under a farther one's front faces, so those runs
                # hold one instance each
                runs[-1][2].append(int(i))
            else:
                runs.append((it.geometry, it.state, [int(i)]))
        calls = 0
        for geometry, state, indices in runs:
            drawer = self._drawers.get(state.kind)
            if drawer is not None:
                made = drawer(self, [items[i] for i in indices], state)
                self._applier.forget()
                self.count(made, len(indices))
                calls += made
                continue
            data = rows[indices]
            uniform = uniform_material(data)
            highlight = bool((data[:, _HIGHLIGHT_ON] > 0.0).any())
            features = self._features(state, uniform, highlight, composed, False)
            prog = self.programs.get(state.kind, features, state.code)
            layout = ROW.subset(instance_fields(state.kind, dict(features)))
            buf, vao = self._transient_vao(geometry, state, prog, layout, len(indices))
            buf.write(np.ascontiguousarray(data[:, self._columns(layout)]).tobytes())
            if uniform:
                self._set_material(prog, data[0])
            raster = list(composed.raster(state.raster, self._defaults))
            if raster[Blend.index] is None:
                raster[Blend.index] = _OVER
            if DepthMask.index not in composed.state:
                raster[DepthMask.index] = False
            self._set_uniforms(prog, state, composed)
            mode = self._mode(geometry, state.kind)
            if _two_faced(geometry, state):
                # back faces first, then front faces: closed transparent shapes blend correctly
                for face in ("front", "back"):
                    raster[CullFace.index] = face
                    self._apply_raster(tuple(raster), state)
                    vao.render(mode, instances=len(indices))
                    self.count(1, len(indices))
                    calls += 1
            else:
                self._apply_raster(tuple(raster), state)
                vao.render(mode, instances=len(indices))
                self.count(1, len(indices))
                calls += 1
        return calls

    def _transient_vao(self, geometry: Geometry, state: DrawState, prog: Any, layout: Any, n: int) -> tuple[Any, Any]:
        key = (id(geometry), id(state), id(prog))
        entry = self._transient.get(key)
        if entry is not None and entry[2] >= n and geometry.buffers is not None:
            return entry[0], entry[1]
        if entry is not None:
            entry[1].release()
            entry[0].release()
        capacity = max(n, 4)
        buf = gpu_call(self.ctx.buffer, reserve=capacity * layout.stride * 4, dynamic=True, what="instance data")
        vao = self._vao(geometry, prog, buf, state.kind, layout)
        self._transient[key] = (buf, vao, capacity, geometry, state)
        return buf, vao

    # -- read back -------------------------------------------------------------
    def read(self, read_depth: bool = True) -> Image:
        """Resolve multisampling and read the image (colour, and eye-space depth unless ``read_depth=False``)."""
        with self.current():
            return self._read(read_depth)

    def _read(self, read_depth: bool) -> Image:
        if self.raw.available:
            # wait for the GPU through ctypes, which releases the GIL (moderngl's resolve and read would wait
            # holding it): other Python threads (an application loop beside render threads) run meanwhile
            self.raw.glFinish()
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


def _same_shape(old: Scope, new: Scope) -> bool:
    """Whether ``new`` has ``old``'s structure: same techniques, and per item the same geometry, state, class."""
    stack = [(old, new)]
    while stack:
        a, b = stack.pop()
        if a.technique is not b.technique or len(a.entries) != len(b.entries):
            return False
        for x, y in zip(a.entries, b.entries, strict=True):
            if x is y:
                continue
            if isinstance(x, Scope):
                if not isinstance(y, Scope):
                    return False
                stack.append((x, y))
            elif (
                isinstance(y, Scope)
                or x.geometry is not y.geometry
                or x.state is not y.state
                or x.transparent != y.transparent
            ):
                return False
    return True


def _positions(scope: Scope) -> dict[int, tuple[Segment, int]]:
    """Entry index -> (segment, position in it) for the items of a planned scope."""
    out: dict[int, tuple[Segment, int]] = {}
    parts = iter(scope.parts or [])
    segment: Segment | None = None
    position = 0
    for i, entry in enumerate(scope.entries):
        if isinstance(entry, Scope):
            segment = None
            continue
        if segment is None or position == len(segment.items):
            part = next(parts)
            while isinstance(part, Scope):
                part = next(parts)
            segment, position = part, 0
        out[i] = (segment, position)
        position += 1
    return out


def _select_from_source(batch: Batch) -> None:
    """Make a filtered batch follow the batch its items come from (their slots), when they all come from one."""
    first = batch.items[0].slot
    if first is None or any(it.slot is None or it.slot[0] is not first[0] for it in batch.items):
        return  # not from one planned batch: made again when the scope is
    source = first[0]
    if batch.items[0].instances is not None:
        batch.picks = None  # an instance set: all its rows
    else:
        batch.picks = np.fromiter((it.slot[1] for it in batch.items), np.int64, len(batch.items))
    batch.source = source
    batch.source_version = source.version


def _replace_in_views(scope: Scope, source: Batch, index: int, item: DrawItem) -> None:
    """``item`` replaced row ``index`` of ``source``: put it into the scope's filtered batches that select it."""
    for batches in scope.filtered.values():
        for group in batches.values():
            for batch in group:
                if batch.source is not source or batch.picks is None:
                    continue
                j = int(np.searchsorted(batch.picks, index))
                if j < len(batch.picks) and batch.picks[j] == index:
                    batch.items[j] = item


def _release_filtered(scope: Scope) -> None:
    for batches in scope.filtered.values():
        for group in batches.values():
            for batch in group:
                batch.release()
    scope.filtered = {}


def _two_faced(geometry: Geometry, state: DrawState) -> bool:
    """Whether a transparent draw renders back faces, then front faces (closed shapes without culling)."""
    return state.value(CullFace) == "none" and geometry.mode == "triangles" and state.kind == "mesh"


_GL_SRGB8_ALPHA8 = 0x8C43
_TRIANGLES_ADJACENCY = 0x000C
_GL_RGBA8 = 0x8058
