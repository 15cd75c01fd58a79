"""Drawing a compiled draw list: instanced batches, the two passes, GL state, read-back.

Opaque items are grouped into batches (one instanced call per geometry and
state; only changed instance rows are uploaded), transparent items are sorted
back to front each frame and drawn with blending and without depth writes,
overlays (text) come last.  Program variants are chosen per draw from the
state's features, the frame's light types and whether a batch shares one
material (then uniforms replace per-instance attributes).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ..image import Image
from .context import GLError, clear_stencil, set_masks
from .drawlist import Batch, DrawItem, DrawState, plan_batches, uniform_material
from .geometry import Geometry
from .lighting import LightUniforms
from .resources import gpu_call
from .shaders import INSTANCE_ATTRIBUTES, INSTANCE_FORMAT, ROW

__all__ = ["BatchRenderer"]

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
_GL_SRGB8_ALPHA8 = 0x8C43
#: Batches with at least this many opaque instances are drawn front to back (re-sorted when the view changes).
SORT_MIN = 64


class BatchRenderer:
    """Mixin of :class:`~omnirender.gl.engine.GLEngine`: batches, passes, GL state and read-back."""

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
        # instance buffers of transparent draws whose (geometry, state) the new list no longer has (e.g. a clip
        # plane or texture that changes every frame gives a new state each frame); entries hold their geometry
        # and state, so these ids cannot be reused while an entry exists
        drawn = {(id(it.geometry), id(it.state)) for it in items if it.transparent}
        for transient in list(self._transient):
            if transient[:2] not in drawn:
                buf, vao, *_ = self._transient.pop(transient)
                vao.release()
                buf.release()
        self.geometry_cache.sweep(used)
        for geom in list(self._uploaded()):
            if id(geom) not in used and not geom.persistent:
                geom.release()
        textures = self.__dict__.get("_textures")
        if textures:
            # textures of attributes the list no longer uses (e.g. re-simplified mesh files) are freed
            live = {id(it.state.texture) for it in items if it.state.texture is not None}
            for key in [k for k in textures if k not in live]:
                textures.pop(key)[2].release()

    def _uploaded(self) -> list[Geometry]:
        return [g for g in self.__dict__.setdefault("_uploaded_set", weakref.WeakSet())]

    def _ensure_uploaded(self, geometry: Geometry) -> None:
        if geometry.buffers is None:
            geometry.upload(self.ctx)
            self.__dict__.setdefault("_uploaded_set", weakref.WeakSet()).add(geometry)

    def draw(self, background: Any = None, clear: bool = True) -> None:
        """Draw the installed draw list into the framebuffer (opaque, transparent sorted, overlays).

        ``clear=False`` draws over what the framebuffer holds (compositing several renderers).
        """
        with self.current():
            self._draw(background, clear)

    def _draw(self, background: Any, clear: bool) -> None:
        ctx = self.ctx
        fbo = self.framebuffer
        _ = ctx.error  # errors of earlier, foreign GL calls are not this frame's
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
        self._view_key = view.tobytes()
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
        # GL_SRGB8_ALPHA8: texture images are display (sRGB) values; the GPU decodes them before filtering
        # and mipmapping, so minified and magnified textures average light, not encoded values
        tex = gpu_call(self.ctx.texture, (w, h), 4, img.tobytes(), internal_format=_GL_SRGB8_ALPHA8, what="a texture")
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
                if src == "src_alpha" and dst == "one_minus_src_alpha":
                    # "over": the alpha channel accumulates coverage (a + (1 - a) dst), so a transparent
                    # background keeps the right opacity
                    ctx.blend_func = (ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA, ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA)
                else:
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
        if stride and n >= SORT_MIN and not state.special:
            # opaque instances front to back: early depth tests then skip hidden fragments
            if batch.dirty is not None or batch.sorted_for != self._view_key:
                view = self._view
                z = batch.rows[:, 12:15] @ view[2, :3]
                order = np.argsort(-z, kind="stable")
                data = batch.rows[order] if stride == ROW else batch.rows[order, :20]
                batch.buffer.write(np.ascontiguousarray(data).tobytes())
                batch.sorted_for = self._view_key
                batch.dirty = None
        elif batch.dirty is not None:
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
                if (
                    runs
                    and runs[-1][0] is it.geometry
                    and runs[-1][1] is it.state
                    and not _two_faced(it.geometry, it.state)
                ):
                    # instances of a two-faced run would draw all back faces, then all front faces: a nearer
                    # instance's back faces would then land under a farther one's front faces, so those runs
                    # hold one instance each
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
                if _two_faced(geometry, state):
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
        self._transient[key] = (buf, vao, capacity, geometry, state)
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


def _two_faced(geometry: Geometry, state: DrawState) -> bool:
    """Whether a transparent draw renders back faces, then front faces (closed shapes without culling)."""
    return state.cull == "none" and geometry.mode == "triangles" and state.kind == "mesh"


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
