"""Issuing the draws of one (composed) pass: instanced batches, sorted transparency, overlays.

The :class:`BatchDrawer` draws the items of a scope that a pass selects:
opaque batches (one instanced call per geometry and state; big batches are
sorted front to back and culled to the frame's view, and only changed rows
are uploaded), transparent items back to front with blending on and depth
writes off (closed transparent shapes: back faces, then front faces), then
overlays (text).  What a pass changes (state overrides, shader features,
camera) is applied per draw from the :class:`~.passes.Composed` pass.

It is one of the engine's collaborators: it reads the pass's camera and
target from the :class:`~.frame_state.FrameState`, names targets through
:class:`~.targets.FrameTargets`, counts into the :class:`~.report.PassReport`,
and uses only the public API of the engine facade it is given (lights,
geometry uploads, render textures, the batches a pass mask keeps).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from .attributes import Blend, CullFace, DepthMask
from .drawlist import Batch, DrawItem, DrawState, Scope, Segment, scatter_translations, uniform_material
from .frame_state import FrameState
from .geometry import Geometry
from .glenum import GL_RGBA8, GL_SRGB8_ALPHA8, GL_TRIANGLES_ADJACENCY
from .layout import ROW
from .lighting import LightUniforms
from .passes import Composed
from .pipelines import apply_sampling
from .renderer import item_filter
from .report import PassReport
from .resources import gpu_call
from .shaders import instance_fields
from .state import LineWidth, ShadowingState, defaults
from .targets import FrameTargets
from .units import PASS_INPUTS, SHADOW_ATLAS

__all__ = ["BatchDrawer", "SORT_MIN", "PASS_INPUT_UNIT", "sorts_instances"]

#: First texture unit of a pass's Shader inputs (the table of units: :mod:`.units`).
PASS_INPUT_UNIT = PASS_INPUTS
#: Batches with at least this many opaque instances are drawn front to back (re-sorted when the view changes).
SORT_MIN = 64
#: An instance set's front-to-back order is kept across moves; after this many changes since it was made it is
#: made again (instances that travelled far would otherwise be drawn in an order that no longer saves depth work).
RESORT_AFTER = 60
#: ``GL_RENDERER`` names of software rasterisers (Mesa's llvmpipe, softpipe, swrast; SwiftShader; Apple's).
_SOFTWARE = ("llvmpipe", "softpipe", "swrast", "swiftshader", "software rasterizer")
_TRANSLATION = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)
_MODEL = ROW.slice("model")
_HIGHLIGHT_ON = ROW.at("highlight", "on")
#: light uniform sets kept between passes and frames (by light switch and view) before they are all dropped
_LIGHTS_KEPT = 16
_OVER = ("src_alpha", "one_minus_src_alpha", "add")
_MATERIAL_UNIFORMS = (("u_spec", "specular"), ("u_emis", "emission"), ("u_amb", "ambient"), ("u_pbr", "pbr"),
                      ("u_hl", "highlight"), ("u_point", "point"))  # fmt: skip


def sorts_instances(renderer: str) -> bool:
    """Whether opaque instance sets are culled and drawn front to back on the GL implementation ``renderer``.

    Only on software rasterisers: there every hidden fragment a front-to-back
    order lets the depth test skip is CPU work (a 10,000-box set drew in 1.5x
    the time in row order on llvmpipe), worth culling the set and gathering
    its moved positions into that order (25 us per 10,000 on the CPU).  A GPU
    rejects hidden fragments itself (hierarchical depth) and clips what is
    out of view, so there the set is drawn in the application's row order and
    a move uploads its positions as they are: the CPU work the frame costs.
    (Mesa's no-op driver, which measures that CPU side, counts as a GPU.)
    """
    name = renderer.lower()
    return any(word in name for word in _SOFTWARE)


class BatchDrawer:
    """Draws what a pass selects of a scope; owns the transient buffers, textures and custom-kind drawers."""

    def __init__(
        self, engine: Any, state: FrameState, targets: FrameTargets, report: PassReport, drawers: dict[str, Any]
    ) -> None:
        #: the engine facade: custom-kind drawers get it, and its public API gives lights, uploads and batches
        self.engine = engine
        self.ctx = engine.ctx
        self.raw = engine.raw
        self.programs = engine.programs
        self.state = state
        self.targets = targets
        self.report = report
        #: drawers for draw-item kinds that are not plain instanced geometry (text, volumes), by kind
        self.drawers = drawers
        self._transient: dict[Any, tuple[Any, ...]] = {}
        self._textures: dict[tuple[int, bool], tuple[Any, int, Any]] = {}
        self._column_cache: dict[tuple[str, ...], np.ndarray] = {}
        self._layouts: dict[tuple[str, ...], Any] = {}
        #: (id(light switch), view) -> (switch, stamp, any scene light, LightUniforms) of earlier passes
        #: (_lights_for): a frame that draws shadow maps alternates the light's view and its own, both kept
        self._lights_kept: dict[tuple[int, bytes], tuple[Any, Any, bool, LightUniforms]] = {}
        #: whether opaque instance sets are culled and drawn front to back (:func:`sorts_instances`)
        self.sorts_instances = sorts_instances(str(self.ctx.info.get("GL_RENDERER", "")))

    def draw_items(self, scope: Scope, composed: Composed, nested: Any) -> int:
        """Draw the items of ``scope`` that ``composed`` selects; ``nested(scope)`` runs a nested technique scope.

        Order: opaque batches and nested scopes as they were met, then
        transparent items back to front, then overlays.
        """
        classes = composed.classes
        calls = 0
        parts = scope.parts or []
        filtered = self.engine.filtered_batches(scope, composed) if (composed.masks or composed.selects) else None
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
                keep = item_filter(composed)
                others = [it for it in others if keep(it)]
        if others and self.state.recorder is not None:
            self.state.recorder.taint("transparent or overlay items (sorted and drawn by the view every frame)")
        if "transparent" in classes and others:
            calls += self._draw_transparent([it for it in others if it.transparent and not it.state.overlay], composed)
        if "overlay" in classes and others:
            for it in others:
                if it.state.overlay:
                    drawer = self.drawers.get(it.state.kind)
                    if drawer is not None:
                        made = drawer(self.engine, [it], it.state)
                        self.report.count(made, 1)
                        calls += made
        return calls

    def _features(self, state: DrawState, uniform: bool, highlight: bool, composed: Composed, single: bool) -> tuple:
        """Program features of a draw: the state's, the lights, the material sharing, the pass's shading."""
        features = state.features
        shading = composed.shading()
        if state.kind in ("mesh", "points"):
            lit = not any(name in ("DEPTH_ONLY", "FLAT_COLOR", "UNLIT") for name, _ in shading)
            if lit:
                if not any(name == "PASS_SURFACE" for name, _ in shading):  # a surface pass lights nothing itself
                    features = features + (("LIGHTS", self._lights_for(state.switch).types),)
                plan = self.state.shadow_plan
                if plan is not None and state.raster[ShadowingState.index][1]:
                    if not any(name == "SHADOWS_OFF" for name, _ in shading):
                        features = features + plan.features()
            if self.state.ortho:
                features = features + (("ORTHO", True),)
            if not uniform:
                features = features + (("INSTANCE_MATERIAL", True),)
            elif single:
                features = features + (("SINGLE", True),)
        if highlight:
            features = features + (("HIGHLIGHT", True),)
        if self.state.linear_output:
            features = features + (("LINEAR_OUTPUT", True),)
        return features + shading

    def _draw_batch(self, batch: Batch, composed: Composed) -> int:
        state = batch.state
        drawer = self.drawers.get(state.kind)
        recorder = self.state.recorder
        if drawer is not None:
            if recorder is not None:
                recorder.taint(f"draw items of kind {state.kind!r} (a drawer of their own)")
            calls = drawer(self.engine, batch.items, state)
            self.report.count(calls, len(batch.items))
            return calls
        n = batch.size
        if not n:
            return 0  # an instance set with no visible instance
        highlight = _highlighted(batch)
        single = n == 1 and batch.uniform and state.kind == "mesh"
        features = self._features(state, batch.uniform, highlight, composed, single)
        offset = not single and _takes_offsets(batch, state, features)
        if offset:
            features = features + (("INSTANCE_OFFSET", True),)
        prog = self.programs.get(state.kind, features, state.code)
        fields = instance_fields(state.kind, dict(features))
        if fields:
            self._ensure_buffers(batch, self._layout(fields), n, offset)
        volume = state.kind == "mesh" and "SHADOW_VOLUME" in dict(features)  # triangles with their neighbours
        vao = batch.vaos.get(id(prog))
        if vao is None:
            vao = batch.vaos[id(prog)] = self._vao(
                batch.geometry, prog, batch.buffer, state.kind, batch.layout, volume, batch.offsets if offset else None
            )
        target = prog if recorder is None else recorder.begin_draw(prog)  # uniforms are written through it
        if fields:
            columns = self._columns(batch.layout)
            if offset:
                n = self._prepare_instance_set(batch, columns, n)
                if not n:
                    return 0
            elif n >= SORT_MIN and not state.special:
                n = self._prepare_sorted(batch, columns, n)
                if not n:
                    return 0
            elif batch.sparse or batch.dirty is not None:
                _upload_rows(batch, columns, None)
        else:
            row = batch.rows[0]
            target["i_model"].write(row[_MODEL].tobytes())
            u = target.get("i_color", None)
            if u is not None:
                u.write(row[ROW.slice("color")].tobytes())
        raster = composed.raster(state.raster, defaults())
        self._apply_raster(raster, state)
        self._set_uniforms(target, state, composed)
        if batch.uniform:
            self._set_material(target, batch.first_row())
        mode = GL_TRIANGLES_ADJACENCY if volume else self._mode(batch.geometry, state.kind)
        vao.render(mode, instances=n)
        if recorder is not None:
            recorder.end_draw(raster, len(state.clip), vao, mode, n, batch)
        self.report.count(1, n)
        return 1

    def _ensure_buffers(self, batch: Batch, layout: Any, n: int, offset: bool) -> None:
        """Give ``batch`` GPU buffers of ``layout`` for its ``n`` rows (and its translations' own buffer when
        ``offset``): made again (every row uploaded) when missing, too small or of another layout."""
        recorder = self.state.recorder
        if batch.buffer is not None and batch.layout is not None and batch.layout.names() != layout.names():
            if recorder is not None:  # vertex arrays recorded earlier in the frame would be released
                recorder.taint("a batch packed again for another program variant")
            batch.release()  # a variant reads other fields: re-pack
        if (
            batch.buffer is None
            or batch.capacity < n
            or batch.geometry.buffers is None
            or (offset and batch.offsets is None)
        ):
            if recorder is not None and batch.vaos:
                recorder.taint("a batch's buffers made again")
            batch.release()
            batch.layout = layout
            # a batch that rows may be added to (it holds spare rows) gets room in its buffer too
            capacity = max(n, 1) + (n // 8 + 16 if batch.storage is not None else 0)
            batch.buffer = gpu_call(
                self.ctx.buffer, reserve=capacity * batch.layout.stride * 4, dynamic=True, what="instance data"
            )
            if offset:
                batch.offsets = gpu_call(self.ctx.buffer, reserve=capacity * 12, dynamic=True, what="instance data")
            batch.capacity = capacity
            batch.dirty = (0, n)
            batch.sparse = None

    def _prepare_sorted(self, batch: Batch, columns: np.ndarray, n: int) -> int:
        """Upload what changed of a big batch; returns how many rows to draw.

        Big batches: opaque instances front to back (early depth tests skip
        hidden fragments) and culled to the frame's view: the buffer holds the
        visible ones first, then the rest, so passes from other cameras
        (shadow maps, mirrors) draw them all from the same buffer; changed rows
        are rewritten where they lie unless culling has to be done again.
        """
        own_view = self.state.view_key == self.state.frame_view_key
        stale = batch.position is None or len(batch.position) != n
        view_key = self.state.view_key
        if stale or (own_view and (batch.sorted_for != view_key or _may_enter_view(batch, n))):
            visible = self._cull(batch) if own_view else None
            z = batch.rows[:, _TRANSLATION] @ self.state.view[2, :3]
            if visible is None:
                order = np.argsort(-z, kind="stable")
                batch.drawn = n
            else:
                seen, hidden = np.nonzero(visible)[0], np.nonzero(~visible)[0]
                order = np.concatenate([seen[np.argsort(-z[seen], kind="stable")], hidden])
                batch.drawn = len(seen)
            packed = _pack(batch.rows, order, columns)
            batch.buffer.write(packed)
            batch.packed = packed  # the buffer's content: moved rows rewrite only their translations
            batch.position = np.empty(n, np.int64)
            batch.position[order] = np.arange(n)
            batch.sorted_for = self.state.view_key if own_view else None
            batch.dirty = None
            batch.sparse = None
        elif batch.sparse or batch.dirty is not None:
            if not own_view and _may_enter_view(batch, n):
                batch.sorted_for = None  # another camera's pass uploads first: culled again in the frame's
            _upload_rows(batch, columns, batch.position)  # the changed rows where they lie
        return batch.drawn if own_view else n

    def upload_moved(self, batch: Batch) -> bool:
        """Upload ``batch``'s changed rows where they lie, as its draw in the frame's own view would, for a
        replayed frame plan (rows moved in place since it was recorded); False, with nothing uploaded, when
        its draw would do more than that: sort or cull it again, pack it again, write a uniform from its row
        (one row).  An instance set's batch uploads its moved positions (:meth:`_upload_moved_instances`)."""
        n = batch.size
        if batch.items and batch.items[0].instances is not None:
            return self._upload_moved_instances(batch, n)
        if not _packed(batch, n):
            return False
        if not (batch.sparse or batch.dirty is not None):
            return True
        state = self.state
        position = None
        if n >= SORT_MIN and not batch.state.special:
            position = batch.position
            if (
                position is None
                or len(position) != n
                or state.view_key != state.frame_view_key
                or batch.sorted_for != state.view_key
                or _may_enter_view(batch, n)
            ):
                return False
        _upload_rows(batch, self._columns(batch.layout), position)
        return True

    def redraw_key(self, batch: Batch) -> tuple[Any, ...] | None:
        """What a draw of ``batch`` in another camera's pass (every row, from its buffers) depends on besides the
        pass: its buffers, layout and geometry and what picks its program variant (a shared material, a
        highlighted row); None when such a draw cannot be issued again as recorded with the rows as they are
        (rows not uploaded yet, one row, an instance set, or the draw would sort or pack again first).

        Two equal keys of the same batch: the recorded draw (vertex array, program, uniforms) draws the
        batch's current rows as :meth:`_draw_batch` would, with ``batch.size`` instances
        (``FrameRunner.replay_draws``)."""
        n = batch.size
        if (
            not _packed(batch, n)
            or batch.sparse
            or batch.dirty is not None
            or self.drawers.get(batch.state.kind) is not None
            or (batch.items and batch.items[0].instances is not None)
        ):
            return None
        if n >= SORT_MIN and not batch.state.special:
            position = batch.position
            if position is None or len(position) != n:
                return None  # its draw would sort and pack it again
        geometry = tuple(batch.geometry.buffers.values())  # (a snapshot: a geometry uploaded again has new ones)
        return (batch.buffer, batch.layout, geometry, batch.uniform, _highlighted(batch))

    def _upload_moved_instances(self, batch: Batch, n: int) -> bool:
        """:meth:`upload_moved` for an instance set's batch: its moved positions uploaded as its draw in the
        frame's own view would (:meth:`_prepare_instance_set`); False when that draw would do more (sort or
        cull again, re-pack rows made again)."""
        state = self.state
        if (
            batch.buffer is None
            or batch.offsets is None
            or batch.position is None
            or len(batch.position) != n
            or (
                self._sorts(batch, n)  # its draw in the frame's own view would sort or cull it again
                and (
                    state.view_key != state.frame_view_key
                    or batch.sorted_for != state.view_key
                    or _may_enter_view(batch, n)
                    or _order_aged(batch)
                )
            )
        ):
            return False
        if not (batch.sparse or batch.dirty is not None):
            return True
        # positions only, else drawn in full
        return _upload_moved_offsets(batch, batch.offset_order)

    def _prepare_instance_set(self, batch: Batch, columns: np.ndarray, n: int) -> int:
        """Upload what changed of an instance set's batch; returns how many instances to draw.

        Culled to the frame's view and sorted front to back like big batches
        (the buffers hold the visible instances nearest first, then the rest).
        The order only speeds drawing up, so it is kept across moves while the
        view holds: a partly culled set that moved is culled again and the
        kept order partitioned, not sorted again (:func:`_depth_order`); while
        all are in view nothing is redone, so a move
        uploads the application's positions taken in that order (one gather)
        to the translations' own buffer (:func:`_upload_instance_set`).  In row
        order instead, llvmpipe shaded the hidden fragments too: a 10,000-box
        set's frame took 1.5x.  That is on software rasterisers only
        (:func:`sorts_instances`); on a GPU the set is drawn in row order, all of
        it, and a move uploads the positions as they are.
        """
        own_view = self.state.view_key == self.state.frame_view_key
        view_key = self.state.view_key
        big = self._sorts(batch, n)
        if (
            batch.position is None
            or len(batch.position) != n
            or (big and own_view and (batch.sorted_for != view_key or _may_enter_view(batch, n) or _order_aged(batch)))
        ):
            visible = self._cull(batch) if own_view and big else None
            order = None
            if big:  # front to back, as other big batches: early depth tests skip hidden fragments
                depth = _depth_order(batch, view_key, self.state.view, n)
                if visible is None:
                    order = depth
                else:  # the visible ones first, in the same order
                    seen = visible[depth]
                    order = np.concatenate([depth[seen], depth[~seen]])
            batch.drawn = n if visible is None else int(visible.sum())
            batch.position = np.arange(n)
            if order is not None:
                batch.position[order] = np.arange(n)
            batch.offset_order = order
            batch.sorted_for = view_key if own_view else None
            batch.sparse = None
            batch.dirty = None
            _upload_instance_set(batch, columns, order, everything=True)
        elif batch.sparse or batch.dirty is not None:
            if not own_view and _may_enter_view(batch, n):
                batch.sorted_for = None  # another camera's pass uploads first: culled again in the frame's
            _upload_instance_set(batch, columns, batch.offset_order)
        return batch.drawn if own_view else n

    def _sorts(self, batch: Batch, n: int) -> bool:
        """Whether an instance set's batch of ``n`` rows is culled and drawn front to back (:func:`sorts_instances`)."""
        return self.sorts_instances and n >= SORT_MIN and not batch.state.special

    def _cull(self, batch: Batch) -> np.ndarray | None:
        """Which instances' bounding spheres meet the view frustum (None: all of them)."""
        return cull_spheres(batch.rows[:, _MODEL], batch.geometry.bounds, self.state.proj @ self.state.view)

    def _layout(self, fields: tuple[str, ...]) -> Any:
        """The instance layout of ``fields`` (in the row's order: compared with a batch's to know whether the
        batch must be packed again)."""
        layout = self._layouts.get(fields)
        if layout is None:
            layout = self._layouts[fields] = ROW.subset(fields)
        return layout

    def _columns(self, layout: Any) -> np.ndarray:
        key = layout.names()
        cols = self._column_cache.get(key)
        if cols is None:
            cols = self._column_cache[key] = layout.columns(ROW)
        return cols

    def _vao(
        self,
        geometry: Geometry,
        program: Any,
        buffer: Any,
        kind: str,
        layout: Any,
        adjacency: bool = False,
        offsets: Any = None,
    ) -> Any:
        self.engine.upload(geometry)
        content = geometry.content(program)
        if buffer is not None and layout is not None:
            fmt, names = layout.vertex_format()
            content.append((buffer, fmt, *names))
        if offsets is not None:  # an instance set's translations (the shader's i_offset)
            content.append((offsets, "3f/i", "i_offset"))
        index = geometry.buffers.get("index") if kind != "points" else None
        if adjacency:
            index = geometry.adjacency_buffer(self.ctx)
        return self.ctx.vertex_array(program, content, index_buffer=index, index_element_size=4, skip_errors=True)

    def _mode(self, geometry: Geometry, kind: str) -> int:
        ctx = self.ctx
        if geometry.mode == "patches":  # tessellated on the GPU (gl/nurbs.py)
            if self.state.recorder is not None:
                self.state.recorder.taint("tessellated patches (patch size set outside the recorder)")
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
        lu = self.state.lights.get(key)
        if lu is None:
            everything = self.engine.scene_lights
            lights = everything
            if switch is not None:
                lights = [(light, m) for light, m in lights if switch.allows(light)]
            view = self.state.view
            # the lights' arrays of an earlier pass with this view while the lights and their placements are the
            # same (kept per view: a shadow map's depth pass does not push out the frame's own)
            kept_key = (key, view.tobytes())
            stamp = tuple([(light, light.version, m.tobytes()) for light, m in lights])
            kept = self._lights_kept.get(kept_key)
            if kept is not None and kept[0] is switch and kept[1] == stamp and bool(everything) == kept[2]:
                lu = kept[3]
            else:
                lu = LightUniforms(lights, view, headlight=not everything)
                if len(self._lights_kept) >= _LIGHTS_KEPT:  # views of a moving camera: the old ones go
                    self._lights_kept.clear()
                self._lights_kept[kept_key] = (switch, stamp, bool(everything), lu)
            self.state.lights[key] = lu
        return lu

    def _set_uniforms(self, prog: Any, state: DrawState, composed: Composed) -> None:
        for name, data in self.state.uniforms.items():
            u = prog.get(name, None)
            if u is not None:
                u.write(data)
        recorder = self.state.recorder
        self._set_lights(prog, state, recorder)
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
            u.value = (self.state.target_size[0] / 2.0, self.state.target_size[1] / 2.0)
            u = prog.get("u_viewport_origin", None)
            if u is not None:  # points: the viewport's corner (a pass's viewport box)
                u.value = tuple(float(v) for v in self.ctx.viewport[:2])
        if state.kind == "lines":
            prog["u_line_width"].value = float(state.value(LineWidth))
        if state.textures:
            self._bind_textures(prog, state, recorder)
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
            if recorder is not None:
                recorder.taint("a pass's shader inputs")
            self._bind_inputs(prog, inputs)

    def _set_lights(self, prog: Any, state: DrawState, recorder: Any) -> None:
        """The lights of the draw's light switch, and the shadow maps' uniforms and atlas."""
        lights = self._lights_for(state.switch)
        if recorder is not None and lights.has_area:
            recorder.taint("area lights (their tables are bound outside the recorder)")
        lights.apply(prog)
        if self.state.shadow_plan is not None and prog.get("u_shadow_atlas", None) is not None:
            plan = self.state.shadow_plan
            atlas = self.targets.named(plan.target.name).depth
            plan.apply(prog, atlas, lights.order)  # binds the atlas to its unit, writes the shadow uniforms
            if recorder is not None:
                recorder.texture(atlas, SHADOW_ATLAS)

    def _bind_textures(self, prog: Any, state: DrawState, recorder: Any) -> None:
        """The draw's textures on units 0, 1, ... (those its program samples)."""
        for unit, (sampler, texture, srgb) in enumerate(state.textures):
            u = prog.get(sampler, None)
            if u is not None:
                gl_texture = self.texture(texture, srgb)
                gl_texture.use(unit)
                if recorder is not None:
                    if getattr(texture, "rendered", False):
                        recorder.taint("a render texture (its pipeline draws it every frame)")
                    recorder.texture(gl_texture, unit)
                u.value = unit

    def _bind_inputs(self, prog: Any, inputs: dict[str, Any]) -> None:
        """Bind a pass's Shader inputs (targets of the frame by name, or textures) from :data:`PASS_INPUT_UNIT`."""
        for unit, (uniform, source) in enumerate(sorted(inputs.items(), key=lambda p: p[0]), start=PASS_INPUT_UNIT):
            u = prog.get(uniform, None)
            if u is not None:
                if isinstance(source, tuple):
                    name, attachment = source
                    target = self.targets.named(name)
                    texture = target.depth if attachment == "depth" else target.texture(attachment)
                else:
                    texture = self.texture(source)  # an om.Texture of the pass
                texture.use(unit)
                u.value = unit

    def _apply_raster(self, raster: tuple, state: DrawState) -> None:
        applier = self.state.applier
        applier.apply(raster)
        applier.clip_planes(len(state.clip))

    def texture(self, attr: Any, srgb: bool = True) -> Any:
        """The GL texture of an ``om.Texture``: sRGB colour data, or linear data (normal, roughness maps)."""
        if getattr(attr, "rendered", False):  # an om.gl.RenderTexture: its pipeline's last image
            return self.engine.pipelines().texture(attr)
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
        internal = GL_SRGB8_ALPHA8 if srgb else GL_RGBA8
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
        z = world @ self.state.view[2, :3] + self.state.view[2, 3]
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
            drawer = self.drawers.get(state.kind)
            if drawer is not None:
                # the item's GL state with the pass's overrides (an anaglyph eye's colour mask, the transparent
                # depth pass's), as a plain item gets it; the drawer then sets what it needs itself
                self._apply_raster(composed.raster(state.raster, defaults()), state)
                made = drawer(self.engine, [items[i] for i in indices], state)
                self.report.count(made, len(indices))
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
            raster = list(composed.raster(state.raster, defaults()))
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
                    self.report.count(1, len(indices))
                    calls += 1
            else:
                self._apply_raster(tuple(raster), state)
                vao.render(mode, instances=len(indices))
                self.report.count(1, len(indices))
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

    # -- resources ---------------------------------------------------------------------
    def sweep(self, items: list[DrawItem]) -> None:
        """Release the transient buffers and textures that the draw list ``items`` no longer uses."""
        drawn = {(id(it.geometry), id(it.state)) for it in items if it.transparent}
        for key in list(self._transient):
            if key[:2] not in drawn:
                buf, vao, *_ = self._transient.pop(key)
                vao.release()
                buf.release()
        if self._textures:
            live = {(id(t), srgb) for it in items for _, t, srgb in it.state.textures}
            for key in [k for k in self._textures if k not in live]:
                self._textures.pop(key)[2].release()

    def live_buffers(self) -> int:
        """Transient instance buffers held now (for leak checks)."""
        return len(self._transient)

    def texture_count(self) -> int:
        """GL textures of ``om.Texture`` attributes held now (for leak checks)."""
        return len(self._textures)

    def release(self) -> None:
        for buf, vao, *_ in self._transient.values():
            vao.release()
            buf.release()
        self._transient.clear()
        for entry in self._textures.values():
            entry[2].release()
        self._textures.clear()


def _two_faced(geometry: Geometry, state: DrawState) -> bool:
    """Whether a transparent draw renders back faces, then front faces (closed shapes without culling)."""
    return state.value(CullFace) == "none" and geometry.mode == "triangles" and state.kind == "mesh"


def cull_spheres(models: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], clip: np.ndarray) -> np.ndarray | None:
    """Which of the instances whose model matrices are the rows of ``models`` ((N, 16), each M transposed, as
    the rows hold them) have the bounding sphere of ``bounds`` meeting the frustum of ``clip`` (None: all).

    Column by column (an (N, 16) @ (16, 6) product for the six distances, the
    axes' squared lengths summed per column): numpy's reductions over short
    axes cost ten times more.
    """
    b0, b1 = bounds
    center = np.append((b0 + b1) / 2.0, 1.0)
    radius = float(np.linalg.norm(b1 - b0)) / 2.0
    planes = np.array([clip[3] + clip[0], clip[3] - clip[0], clip[3] + clip[1], clip[3] - clip[1],
                       clip[3] + clip[2], clip[3] - clip[2]])  # fmt: skip
    planes /= np.linalg.norm(planes[:, :3], axis=1)[:, None]
    m = models.astype(np.float64)  # m[:, 4r + c] = M[c, r]: column r of M is m[:, 4r : 4r + 4]
    # distance_j = planes_j . (M @ center) = sum over r, c of center[r] * planes[j, c] * M[c, r]
    distance = m @ (center[:, None, None] * planes.T[None, :, :]).reshape(16, 6)
    longest = None  # the longest axis of M's 3x3 part, squared: the sphere's radius scales with it
    for r in range(3):
        axis = m[:, 4 * r] ** 2 + m[:, 4 * r + 1] ** 2 + m[:, 4 * r + 2] ** 2
        longest = axis if longest is None else np.maximum(longest, axis, out=longest)
    limit = -radius * np.sqrt(longest)
    visible = distance[:, 0] > limit
    for j in range(1, 6):
        visible &= distance[:, j] > limit
    return None if visible.all() else visible


def _depth_order(batch: Batch, view_key: Any, view: np.ndarray, n: int) -> np.ndarray:
    """An instance set's rows front to back for the view ``view_key``: the batch's kept order while it is that
    view's, the count holds and it is not aged (moved instances keep their places: the order only speeds
    drawing up), else sorted now by view depth."""
    kept = batch.depth_order
    if kept is not None and kept[0] == view_key and len(kept[1]) == n and not _order_aged(batch):
        return kept[1]
    z = batch.rows[:, _TRANSLATION] @ view[2, :3]
    order = np.argsort(-z, kind="stable")
    batch.depth_order = (view_key, order, batch.version)
    return order


def _order_aged(batch: Batch) -> bool:
    """Whether an instance set's kept front-to-back order has seen :data:`RESORT_AFTER` changes (amortised:
    one sort per so many moves)."""
    kept = batch.depth_order
    return kept is not None and batch.version - kept[2] >= RESORT_AFTER


def _packed(batch: Batch, n: int) -> bool:
    """Whether ``batch``'s ``n`` rows are drawn from its own packed instance buffer (more than one row, a layout,
    room for them all, no separate offsets buffer, geometry uploaded): the rows a recorded draw reads."""
    return (
        n > 1
        and batch.buffer is not None
        and batch.layout is not None
        and batch.offsets is None
        and batch.capacity >= n
        and batch.geometry.buffers is not None
    )


def _may_enter_view(batch: Batch, n: int) -> bool:
    """Whether changed rows of a batch culled to the frame's view may have entered it: some rows are culled and a
    range of rows changed, or one of the few changed rows (``sparse``) was among the culled ones."""
    if batch.drawn >= n:
        return False
    if batch.dirty:
        return True
    if batch.sparse:
        position, drawn = batch.position, batch.drawn
        return any(i >= len(position) or position[i] >= drawn for i in batch.sparse)
    return False


def _upload_rows(batch: Batch, columns: np.ndarray, position: np.ndarray | None) -> None:
    """Upload the batch's few changed rows (``sparse``) where they lie in its buffer; then the dirty range.

    ``batch.packed`` mirrors the buffer: when only translations moved since
    the last upload (``Batch.moved``), just those columns of the mirror are
    rewritten before the range is uploaded, instead of packing every field
    of the rows again.
    """
    stride = batch.layout.stride * 4
    rows = batch.rows
    packed = batch.packed
    sparse = batch.sparse or ()
    for index in sparse if len(sparse) == 1 else sorted(set(sparse)):
        place = index if position is None else int(position[index])
        data = rows[index].take(columns)
        batch.buffer.write(data, offset=place * stride)
        if packed is not None:
            if place < len(packed):
                packed[place] = data
            else:
                packed = batch.packed = None  # a row beyond the mirror: made again with the next full upload
    batch.sparse = None
    if batch.dirty is None:
        return
    lo, hi = batch.dirty
    model = batch.layout.offsets.get("model")
    if packed is not None and model is not None and batch.moved_range == (batch.version, lo, hi):
        places: Any = slice(lo, hi) if position is None else position[lo:hi]
        scatter_translations(packed, model + 12, places, rows[lo:hi])
        first, last = (lo, hi) if position is None else (int(places.min()), int(places.max()) + 1)
        batch.buffer.write(packed[first:last], offset=first * stride)
    elif position is None:
        data = _pack(rows[lo:hi], None, columns)
        batch.buffer.write(data, offset=lo * stride)
        if packed is not None and hi <= len(packed):
            packed[lo:hi] = data
        elif lo == 0 and hi == len(rows):
            batch.packed = data
    else:
        where = position[lo:hi]
        first, last = int(where.min()), int(where.max()) + 1
        order = np.empty(len(rows), np.int64)
        order[position] = _arange(len(rows))
        data = _pack(rows, order[first:last], columns)
        batch.buffer.write(data, offset=first * stride)
        if packed is not None and last <= len(packed):
            packed[first:last] = data
        elif first == 0 and last == len(rows):
            batch.packed = data
    batch.dirty = None


#: program kinds whose vertex shader reads ``i_offset`` under ``INSTANCE_OFFSET`` (shaders.py)
_OFFSET_KINDS = frozenset(("mesh", "points", "lines"))


def _takes_offsets(batch: Batch, state: DrawState, features: tuple) -> bool:
    """Whether ``batch`` is an instance set's, drawn with its translations in a buffer of their own."""
    items = batch.items
    return (
        bool(items)
        and items[0].instances is not None
        and state.kind in _OFFSET_KINDS
        and not any(name == "NURBS" for name, _ in features)
    )


def _highlighted(batch: Batch) -> bool:
    """Whether some row of ``batch`` is highlighted; the answer is kept while the batch's version holds.

    (Rows change only through changes that count a version, new rows forget
    the answer, and a move keeps it: :meth:`Batch.moved`, :meth:`Batch.row_moved`.
    Reading the rows is a strided pass over every row (a pass redrawing a
    region of a shadow map after one moved caster paid it for 10,000 rows);
    for an instance set it would also write the translations a move left
    pending.)
    """
    seen = batch.highlight_seen
    if seen is not None and seen[0] == batch.version:
        return seen[1]
    flag = bool((batch.rows[:, _HIGHLIGHT_ON] > 0.0).any())
    batch.highlight_seen = (batch.version, flag)
    return flag


def _upload_instance_set(batch: Batch, columns: np.ndarray, order: np.ndarray | None, everything: bool = False) -> None:
    """Upload an instance set's batch: rows in buffer ``order`` (None: row order), translations in ``offsets``.

    When only the positions moved since the last upload (``Batch.moved`` with
    ``moved_offsets`` of the same version), only the (N, 3) float32
    translations are written, to the offsets buffer: the array as it is in
    row order, else taken in buffer order.  Any other change rewrites both
    buffers.
    """
    if not everything and _upload_moved_offsets(batch, order):
        return
    batch.buffer.write(_pack(batch.rows, order, columns))
    translations = batch.rows[:, _TRANSLATION] if order is None else np.take(batch.rows[:, _TRANSLATION], order, axis=0)
    batch.offsets.write(np.ascontiguousarray(translations))
    batch.packed = None
    batch.sparse = None
    batch.dirty = None


def _upload_moved_offsets(batch: Batch, order: np.ndarray | None) -> bool:
    """When only the positions moved since the last upload (``Batch.moved`` with ``moved_offsets`` of the same
    version), upload just them to the offsets buffer (row order: the array as it is; else taken in ``order``);
    False, with nothing uploaded, otherwise."""
    moved = batch.moved_offsets  # kept for batches following this one (Batch.follow) while its version holds
    mr = batch.moved_range
    if (
        moved is None
        or mr is None
        or not mr[0] == batch.version == moved[0]
        or batch.sparse
        or len(moved[1]) != batch.size
    ):
        return False
    batch.offsets.write(moved[1] if order is None else np.take(moved[1], order, axis=0))
    batch.dirty = None
    return True


_ARANGE = np.arange(0)


def _arange(n: int) -> np.ndarray:
    """``np.arange(n)`` from a cached array (grown when needed)."""
    global _ARANGE
    if len(_ARANGE) < n:
        _ARANGE = np.arange(max(n, 2 * len(_ARANGE)))
    return _ARANGE[:n]


def _pack(rows: np.ndarray, order: np.ndarray | None, columns: np.ndarray) -> np.ndarray:
    """The GPU content of ``rows`` (those of ``order``, in that order; None: all) restricted to ``columns``.

    A new C-contiguous float32 array (buffers are written from it directly).
    Rows first, then columns, each a plain ``take`` (one fancy index over both
    axes costs several times more).
    """
    picked = rows if order is None else np.take(rows, order, axis=0)
    return np.take(picked, columns, axis=1)
