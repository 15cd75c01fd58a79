"""The deferred pipeline (guacamole): geometry, lighting, shading and compositing passes.

:class:`Deferred` is a GL technique: put it at the top of a scene (or anywhere: it scopes the rest
of its node) or select it for every frame with ``GLEngine(pipeline="deferred")``.  Its passes:

1. **geometry** (``Pass(scopes="items", target=G-buffer, shader=Shader(surface=...))``): every
   opaque item it can shade is drawn with the forward engine's own mesh shader, whose surface
   (textures, vertex colours, normal maps, clip planes, flat shading, points) is handed to the
   visibility stage of the item's shading model; the G-buffer gets depth, normal, material id,
   flags and the model's outputs, the L-buffer the light that needs no source (ambient, emission);
2. **lighting** (custom): every light is drawn as its proxy (:mod:`.proxies`), instanced per kind,
   adding each model's lighting stage into the L-buffer, with the frame's shadow maps;
3. **shading** (custom, full screen): each model's shading stage, fog, colour and depth into the frame;
4. **compositing**: what the G-buffer cannot hold is drawn by the forward technique over the shaded
   image with its depth: opaque items it does not shade (lines, text, highlighted or light-switched
   items, stencil or colour-mask state, mirrors) and nested techniques' scopes, then transparent
   items sorted back to front (as the forward pipeline draws them: the same images, and exact for
   shapes that do not intersect; weighted blended OIT would differ from the forward pipeline), volumes
   ray cast against the G-buffer depth, overlays.

:class:`DeferredRenderer` (``engine.pipeline``) is the engine's side: the layout of the frame's
shading models, the generated programs (compiled once per set of models and cached), the material
table, the light proxies; ``describe()`` prints the buffers.
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np

from ..engine.attributes import (
    Blend,
    ColorMask,
    CullFace,
    DepthClamp,
    DepthMask,
    DepthTest,
    ScissorTest,
    StencilOp,
    StencilTest,
)
from ..engine.context import clear_stencil_value, frame_has_stencil, sample_positions, sharing_depth
from ..engine.drawlist import DrawItem
from ..engine.glenum import GL_SAMPLES
from ..engine.layout import ROW
from ..engine.passes import Clear, Pass, Shader, Target
from ..engine.state import FillMode, MirrorState
from ..engine.technique import GLTechnique
from ..engine.units import MATERIAL_TABLE
from ..techniques.forward import Forward
from ..techniques.shadows import ATLAS
from .glsl import (
    FOG_SLOTS,
    depth_program,
    explain,
    lighting_program,
    pixels_program,
    shading_program,
    surface_snippet,
    vertex_snippet,
)
from .layout import GBUFFER, LIGHT_FORMATS, BufferLayout
from .models import PHONG, ShadingModelError, model_by_number
from .proxies import ATTRIBUTES, FULLSCREEN, STRIDE, LightTable, proxy_meshes

__all__ = ["Deferred", "DeferredRenderer", "in_gbuffer", "TABLE_UNIT"]

#: Texture unit of the material table in the geometry pass (the table of units: ``engine/units.py``).
TABLE_UNIT = MATERIAL_TABLE
_HIGHLIGHT_ON = ROW.at("highlight", "on")
_SHADED_KINDS = ("mesh", "points")
#: GL state kinds an item may set and still go through the G-buffer (the rest keep it in the forward passes).
_REJECTING = (Blend, ColorMask, DepthMask, DepthTest, StencilTest, StencilOp)
#: Stencil bits the pipeline marks in the frame for the lighting and shading passes (cleared after shading):
#: where the G-buffer's surface is the one seen, and pixels whose samples are lit one by one (edges).
_WON, _EDGE = 0x40, 0x80


def _inline(technique: Any) -> bool:
    """Whether the G-buffer takes the items of a nested technique's scope (its passes only set receivers)."""
    return bool(getattr(technique, "deferred_inline", False))


def in_gbuffer(item: DrawItem) -> bool:
    """Pass predicate: the deferred pipeline shades ``item`` through the G-buffer (else the forward passes draw it).

    Opaque filled meshes and points without a light switch, highlight, mirror or order-dependent GL state,
    whose techniques below the nearest :class:`Deferred` only set shadow receivers.
    """
    state = item.state
    if item.transparent or state.overlay or state.kind not in _SHADED_KINDS or state.special:
        return False
    if state.switch is not None or item.row[_HIGHLIGHT_ON] > 0.0 or state.raster[MirrorState.index] is not None:
        return False
    for kind in _REJECTING:
        if state.raster[kind.index] != kind.default:
            return False
    if state.raster[FillMode.index]:
        return False  # wireframe surfaces: lines of one pixel are all edge, shaded per sample they would differ
    techniques = item.techniques
    for k in range(len(techniques) - 1, -1, -1):
        if isinstance(techniques[k], Deferred):
            break
        if not _inline(techniques[k]):
            return False
    return True


def forward_drawn(item: DrawItem) -> bool:
    """Pass predicate: the complement of :func:`in_gbuffer` (what the compositing passes draw)."""
    return not in_gbuffer(item)


class Deferred(GLTechnique):
    """The deferred shading pipeline for the rest of its node (the whole scene at the top of the root).

    Nested techniques run in the compositing passes with the forward technique, except those that only
    set shadow receivers (``om.gl.ShadowMaps``), whose items go through the G-buffer.  POV-Ray and the
    other engines ignore it.
    """

    __slots__ = ("light_format",)
    #: The passes of a deferred frame, in order, as data (like ``Forward.PASSES``): the G-buffer, lighting,
    #: shading and forward-opaque passes are described per frame by the :class:`DeferredRenderer` method
    #: named here (they depend on the frame's buffer layout and samples), the rest are ``Forward``'s passes
    #: for what the G-buffer does not hold.
    PASSES: tuple[tuple[str, str | Pass], ...] = (
        ("geometry", "geometry_pass"),
        ("lighting", "lighting_pass"),
        ("shading", "shading_pass"),
        ("opaque", "forward_opaque_pass"),
        *((p.name, p) for p in Forward.PASSES[1:]),
    )
    PASS_NAMES = tuple(name for name, _ in PASSES)

    def __init__(self, light_format: str = "f2") -> None:
        super().__init__(passes=len(self.PASSES))
        if light_format not in LIGHT_FORMATS:
            raise ValueError(f"Deferred: light_format must be one of {LIGHT_FORMATS}, got {light_format!r}")
        #: the L-buffer's texel format: "f2" (half floats) or "r11g11b10f" (compact: 16 bytes per Phong pixel)
        self.light_format = light_format

    def start(self, engine: Any) -> None:
        DeferredRenderer.of(engine).begin(engine, self)

    def prepare_pass(self, engine: Any) -> None:
        engine.set_pass(DeferredRenderer.of(engine).describe_pass(self, engine, engine.current_pass))


class DeferredRenderer:
    """An engine's deferred pipeline: layout, programs, material table upload, light proxies, passes."""

    def __init__(self, engine: Any) -> None:
        self.engine = engine
        self.layout: BufferLayout | None = None
        self._frame_key: Any = None
        self._summary: tuple[bool, bool] = (True, True)
        self._fogs: list[tuple] = []
        self._fog_uniforms: dict[str, tuple[float, ...]] = {}
        self._checked: set[int] = set()
        self._programs: dict[tuple, Any] = {}
        self._vaos: dict[tuple, Any] = {}
        self._meshes: dict[str, tuple[Any, Any]] = {}
        self._instances: dict[tuple, Any] = {}
        self._light_fbos: dict[Any, Any] = {}
        self._fits: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._frame_path: tuple[bool, int] = (False, 0)
        self._lights: tuple[Any, LightTable] | None = None
        self._passes: dict[tuple, Pass] = {}
        self.stats: dict[str, Any] = {}

    @classmethod
    def of(cls, engine: Any) -> DeferredRenderer:
        """The engine's deferred renderer (made on first use, released with the engine)."""
        found = engine.deferred_renderer
        if found is None:
            found = engine.deferred_renderer = cls(engine)
        return found

    # -- what the frame holds ----------------------------------------------------------------------
    def update(self, engine: Any, technique: Deferred) -> None:
        """Models, fogs and whether selections are needed: recomputed when the draw list changed."""
        key = (id(engine.root_scope), engine.draw_list_version, technique.light_format)
        if key == self._frame_key:
            return
        self._frame_key = key
        items = engine.draw_items
        numbers: set[int] = set()
        fogs: list[tuple] = []
        others = any(not _inline(s.technique) for s in engine.scopes[1:])
        for item in items:
            if item.transparent or item.state.overlay:
                continue
            if not in_gbuffer(item):
                others = True
                continue
            numbers.add(int(dict(item.state.features).get("MODEL", PHONG.number)))
            fog = item.state.fog
            if fog is not None and fog not in fogs:
                fogs.append(fog)
        models = [model_by_number(n) or PHONG for n in sorted(numbers)] or [PHONG]
        layout = BufferLayout(models, technique.light_format)
        if self.layout is None or self.layout.key != layout.key:
            self.layout = layout  # rebuilt (with its programs) only when the set of models changes
            self._passes.clear()
        self._summary = (not others, others)
        if len(fogs) > FOG_SLOTS:
            import warnings

            warnings.warn(
                f"GLEngine (deferred): {len(fogs)} different fogs in one frame; the G-buffer has {FOG_SLOTS} fog "
                "slots, the shapes under the others are drawn without fog",
                stacklevel=5,
            )
        self._fogs = fogs[:FOG_SLOTS]
        table = np.zeros((FOG_SLOTS, 4), np.float32)
        colors = np.zeros((FOG_SLOTS, 3), np.float32)
        for k, (color, start, end, density, mode) in enumerate(self._fogs):
            table[k] = (start, end, density, mode)
            colors[k] = color
        self._fog_uniforms = {"u_fogs": tuple(table.ravel().tolist()), "u_fog_colors": tuple(colors.ravel().tolist())}
        self._passes.clear()

    def begin(self, engine: Any, technique: Deferred) -> None:
        """A run of ``technique`` starts: the frame's models and fogs, each new model compiled once, the
        material table bound for the geometry pass."""
        self.update(engine, technique)
        self._check_models(engine)
        engine.material_table.texture(engine.ctx).use(TABLE_UNIT)

    def describe_pass(self, technique: Deferred, engine: Any, index: int) -> Pass:
        """The description of pass ``index`` of ``technique`` in this frame (``Deferred.PASSES[index]``)."""
        frame_level = engine.at_frame_level()
        samples = current_samples(engine)
        key = (index, samples, frame_level)
        found = self._passes.get(key)
        if found is not None:
            return found
        name, how = technique.PASSES[index]
        if isinstance(how, Pass):
            made = how
        else:
            all_in, others = self._summary if frame_level else (False, True)
            made = getattr(self, how)(name, samples, all_in, others)
        self._passes[key] = made
        return made

    def geometry_pass(self, name: str, samples: int, all_in: bool, others: bool) -> Pass:
        """The G-buffer pass: the opaque items the G-buffer holds (every item below, nested scopes' too)."""
        layout = self.layout
        assert layout is not None
        shader = Shader(
            surface=surface_snippet(layout),
            vertex=vertex_snippet(layout),
            uniforms={**self._fog_uniforms, "u_materials": TABLE_UNIT},
        )
        return Pass(
            name,
            items="opaque",
            select=None if all_in else in_gbuffer,
            scopes="items",
            target=layout.target(samples),
            clear=Clear(color=(0.0, 0.0, 0.0, 0.0), depth=1.0),
            shader=shader,
        )

    def lighting_pass(self, name: str, samples: int, all_in: bool, others: bool) -> Pass:
        """The light proxies into the L-buffer (:meth:`lighting`)."""
        return Pass(name, items="none", scopes=False, custom=self.lighting)

    def shading_pass(self, name: str, samples: int, all_in: bool, others: bool) -> Pass:
        """The full-screen shading of the G- and L-buffers into the frame (:meth:`shading`)."""
        return Pass(name, items="none", scopes=False, custom=self.shading)

    def forward_opaque_pass(self, name: str, samples: int, all_in: bool, others: bool) -> Pass:
        """The opaque items the G-buffer does not hold, drawn forward (nothing when it holds them all)."""
        return Pass(name, items="opaque", select=forward_drawn) if others else Pass(name, items="none", scopes=False)

    def _check_models(self, engine: Any) -> None:
        """Compile each new model's stages once, before any frame uses them: errors name model, stage and line."""
        layout = self.layout
        assert layout is not None
        for model in layout.models:
            if model.number in self._checked:
                continue
            single = BufferLayout([model])
            try:
                if "lighting" in model.stages:
                    self._program(engine, ("check-light", model.number),
                                  *lighting_program(single, "point", False, 0, {}))  # fmt: skip
                self._program(engine, ("check-shade", model.number), *shading_program(single, 0, {}))
                probe = engine.programs  # the geometry pass's mesh program, with the visibility stage
                from ..engine.passes import Composed

                composed = Composed().then(
                    Pass("check", shader=Shader(surface=surface_snippet(single), vertex=vertex_snippet(single)))
                )
                probe.get("mesh", (("MODEL", model.number), *composed.shading()), ())
            except ShadingModelError:
                raise
            except ValueError as exc:
                found = explain(str(exc), (model,), "geometry pass")
                raise (found or exc) from None
            self._checked.add(model.number)

    # -- programs and buffers ----------------------------------------------------------------------
    def _program(self, engine: Any, key: tuple, vertex: str, fragment: str) -> Any:
        prog = self._programs.get(key)
        if prog is None:
            try:
                prog = engine.ctx.program(vertex_shader=vertex, fragment_shader=fragment)
            except Exception as exc:
                layout = self.layout
                models = layout.models if layout is not None else ()
                found = explain(str(exc), models, f"{key[0]} program")
                if found is not None:
                    raise found from None
                raise ShadingModelError(f"deferred pipeline: the {key[0]} program failed to compile: {exc}") from None
            self._programs[key] = prog
        return prog

    def _mesh(self, engine: Any, name: str) -> tuple[Any, Any]:
        found = self._meshes.get(name)
        if found is None:
            positions, indices = proxy_meshes()[name]
            ctx = engine.ctx
            found = self._meshes[name] = (ctx.buffer(positions.tobytes()), ctx.buffer(indices.tobytes()))
        return found

    def _vao(self, engine: Any, prog: Any, mesh: str, capacity: int) -> tuple[Any, Any]:
        key = (id(prog), mesh)
        found = self._vaos.get(key)
        if found is not None and found[2] >= capacity:
            return found[0], found[1]
        if found is not None:
            found[0].release()
            found[1].release()
        ctx = engine.ctx
        vbo, ibo = self._mesh(engine, mesh)
        size = max(capacity, 16)
        buf = ctx.buffer(reserve=size * STRIDE * 4, dynamic=True)
        fmt = " ".join(f"{n}f" for _, n in ATTRIBUTES) + "/i"
        vao = ctx.vertex_array(
            prog, [(vbo, "3f", "in_position"), (buf, fmt, *(a for a, _ in ATTRIBUTES))], ibo, 4, skip_errors=True
        )
        self._vaos[key] = (vao, buf, size)
        return vao, buf

    def _light_table(self, engine: Any) -> LightTable:
        plan = engine.frame_shadows
        faces = plan.light_faces if plan is not None else {}
        lights = engine.scene_lights
        key = (tuple((light, light.version, m.tobytes()) for light, m in lights), id(plan))
        if self._lights is None or self._lights[0] != key:
            self._lights = (key, LightTable(lights, faces))
        return self._lights[1]

    def _frame_defines(self, engine: Any) -> dict[str, Any]:
        defines: dict[str, Any] = {}
        if engine.frame_orthographic:
            defines["ORTHO"] = True
        return defines

    def _bind_buffers(self, engine: Any, prog: Any, gbuffer: Any, ambient: bool, extra: dict | None = None) -> None:
        """Bind the G-buffer layers (the light layers with ``ambient``), the material table, ``extra`` textures,
        and set the camera and sample uniforms ``prog`` reads."""
        unit = 0
        textures = [("u_fixed", gbuffer.texture("fixed")), ("u_depth", gbuffer.depth)]
        for name, _fmt in self.layout.layers[1:]:  # type: ignore[union-attr]
            if name not in self.layout.light_layers or ambient:  # type: ignore[union-attr]
                textures.append((f"u_{name}", gbuffer.texture(name)))
        textures.append(("u_materials", engine.material_table.texture(engine.ctx)))
        textures += list((extra or {}).items())
        for uniform, texture in textures:
            u = prog.get(uniform, None)
            if u is not None:
                texture.use(unit)
                u.value = unit
                unit += 1
        view, proj = engine.frame_view, engine.frame_projection
        for name, value in (
            ("u_inv_proj", np.linalg.inv(proj)),
            ("u_eye_to_world", np.linalg.inv(view)),
            ("u_proj", proj),
        ):
            u = prog.get(name, None)
            if u is not None:
                u.write(value.T.astype(np.float32).tobytes())
        u = prog.get("u_size", None)
        if u is not None:
            u.value = tuple(float(v) for v in gbuffer.size)
        fit_u, offsets_u = prog.get("u_fit", None), prog.get("u_offsets", None)
        if fit_u is not None or offsets_u is not None:  # the samples' positions, the plane through their depths
            fit, offsets = self._fit(engine, gbuffer.description.samples)
            if fit_u is not None:
                fit_u.write(fit.tobytes())
            if offsets_u is not None:
                offsets_u.write(offsets.tobytes())

    # -- the lighting pass ---------------------------------------------------------------------------
    def lighting(self, engine: Any, draw: Any) -> int:
        """The G-buffer depth into the frame, then every light's proxy into the L-buffer (additive).

        Without multisampling the proxies are depth tested against the frame's depth in hardware (the
        L-buffer layers share it); with it, a per-pixel pass first finds the pixels that show one surface
        (lit once at the centre) and the edges (lit per sample into one target per sample).
        """
        layout = self.layout
        assert layout is not None
        gbuffer = engine.target(GBUFFER)
        samples = gbuffer.description.samples
        engine.default_gl_state()
        stencil = frame_has_stencil(engine.raw)
        if samples > 1:
            self._fit(engine, samples)  # the sample positions are those of the frame bound now
        calls = self._depth_pass(engine, gbuffer, stencil)
        self._frame_path = (stencil, samples)
        if samples > 1:
            calls += draw(Pass("pixels", target=_PIXELS, custom=self._pixels_pass))
        if not layout.has_lbuffer:
            return calls
        if samples > 1:
            names = tuple(f"{name}_s{k}" for name in layout.light_layers for k in range(samples))
            target = Target(_LIGHTS, colors=names, formats=(layout.light_format,) * len(names), depth=_PIXELS.name,
                            relative="enclosing")  # fmt: skip
            calls += draw(Pass("lights", target=target, clear=Clear(color=(0.0, 0.0, 0.0, 0.0), depth=None),
                               custom=self._lights_pass))  # fmt: skip
            return calls
        frame = engine.current_framebuffer
        shared = self._shared(engine, gbuffer, frame)
        fbo = shared[0] if shared is not None else self._plain_light_fbo(engine, gbuffer)
        size = engine.target_size
        engine.bind_framebuffer(fbo, gbuffer.size)
        try:
            calls += self._draw_lights(engine, fbo, depth_test=shared is not None)
        finally:
            engine.bind_framebuffer(frame, size)
        return calls

    def _lights_pass(self, engine: Any, draw: Any) -> int:
        return self._draw_lights(engine, engine.current_framebuffer, depth_test=True)

    def _draw_lights(self, engine: Any, fbo: Any, depth_test: bool) -> int:
        """Every light's proxy into the bound light targets, instanced per kind (one draw per kind and proxy)."""
        layout = self.layout
        assert layout is not None
        ctx = engine.ctx
        gbuffer = engine.target(GBUFFER)
        samples = gbuffer.description.samples
        engine.default_gl_state()
        # lights add up; the proxies' back faces (one fragment per pixel, also with the camera inside a proxy)
        # behind the surface ("gequal": the surface may be inside), not clipped by the far plane
        engine.apply_gl_state(*_LIGHTS_STATE)
        defines = self._frame_defines(engine)
        plan = engine.frame_shadows
        if plan is not None:
            defines.update(dict(plan.features()))
        extra = {"u_pixels": engine.target(_PIXELS.name).texture("pixel")} if samples > 1 else {}
        table = self._light_table(engine)
        calls = lights = 0
        try:
            for kind, proxy, rows in table.instances(engine.frame_view):
                fullscreen = proxy == FULLSCREEN
                engine.apply_gl_state(*_PROXY_STATE[fullscreen, depth_test and not fullscreen])
                key = ("lighting", layout.key, kind, fullscreen, samples, tuple(sorted(defines.items())))
                prog = self._program(engine, key, *lighting_program(layout, kind, fullscreen, samples, defines))
                self._bind_buffers(engine, prog, gbuffer, ambient=False, extra=extra)
                if plan is not None and prog.get("u_shadow_atlas", None) is not None:
                    plan.apply(prog, engine.target(ATLAS).depth, [])
                vao, buf = self._vao(engine, prog, proxy, len(rows))
                buf.write(rows.tobytes())
                vao.render(ctx.TRIANGLES, instances=len(rows))
                calls += 1
                lights += len(rows)
        finally:
            engine.default_gl_state()
        engine.count(calls, lights)
        self.stats["lights"] = lights
        return calls

    def _pixels_pass(self, engine: Any, draw: Any) -> int:
        """Per pixel of a multisampled G-buffer: the centre's depth, whether it is an edge (:func:`pixels_program`)."""
        gbuffer = engine.target(GBUFFER)
        samples = gbuffer.description.samples
        engine.default_gl_state()
        engine.apply_gl_state(_ALWAYS)  # the pass writes every pixel's nearest depth
        prog = self._program(engine, ("pixels", samples), *pixels_program(samples))
        self._bind_buffers(engine, prog, gbuffer, ambient=False)
        vao, _ = self._vao(engine, prog, FULLSCREEN, 1)
        vao.render(engine.ctx.TRIANGLES, instances=1)
        engine.count(1, 0)
        return 1

    def _depth_pass(self, engine: Any, gbuffer: Any, stencil: bool) -> int:
        """The G-buffer's depth into the frame (depth test less: a scope below the top keeps nearer content),
        sample by sample under a sample mask; with a stencil, the samples where it won get the mark ``_WON``."""
        ctx = engine.ctx
        samples = gbuffer.description.samples
        prog = self._program(engine, ("depth", samples), *depth_program(samples))
        self._bind_buffers(engine, prog, gbuffer, ambient=False)
        engine.apply_gl_state(*(_DEPTH_STATE + (_MARK_STATE if stencil else ())))
        vao, _ = self._vao(engine, prog, FULLSCREEN, 1)
        draws = range(samples) if samples > 1 else (None,)
        for k in draws:
            _mask_sample(engine, prog, k)
            vao.render(ctx.TRIANGLES, instances=1)
        _mask_sample(engine, prog, None)
        engine.default_gl_state()
        engine.count(len(draws), 0)
        return len(draws)

    def _shared(self, engine: Any, gbuffer: Any, frame: Any) -> tuple[Any, Any, bool] | None:
        """The L-buffer layers with the frame's depth (and stencil), or None when the frame's cannot be shared."""
        layout = self.layout
        assert layout is not None
        key = (id(gbuffer), frame.glo)
        found = self._light_fbos.get(key)
        if found is None or found[0] is not gbuffer:
            self._release_fbos()
            colors = [gbuffer.texture(name) for name in layout.light_layers]
            made = sharing_depth(engine.ctx, engine.raw, colors, gbuffer.description.samples)
            found = self._light_fbos[key] = (gbuffer, made)
        return found[1]

    def _plain_light_fbo(self, engine: Any, gbuffer: Any) -> Any:
        key = (id(gbuffer), "plain")
        found = self._light_fbos.get(key)
        if found is None or found[0] is not gbuffer:
            colors = [gbuffer.texture(name) for name in self.layout.light_layers]  # type: ignore[union-attr]
            fbo = engine.ctx.framebuffer(colors)
            found = self._light_fbos[key] = (gbuffer, (fbo, fbo.release, False))
        return found[1][0]

    def _release_fbos(self) -> None:
        for _, made in self._light_fbos.values():
            if made is not None:
                made[1]()
        self._light_fbos.clear()

    def _fit(self, engine: Any, samples: int) -> tuple[np.ndarray, np.ndarray]:
        """Per sample: weights of the least-squares plane through the samples' depths (centre value, slopes),
        and the sample's offset from the pixel centre."""
        found = self._fits.get(samples)
        if found is None:
            offsets = np.asarray(sample_positions(engine.raw, samples)) - 0.5
            design = np.column_stack([np.ones(samples), offsets])
            found = self._fits[samples] = (np.linalg.pinv(design).T.astype(np.float32), offsets.astype(np.float32))
        return found

    # -- the shading pass ----------------------------------------------------------------------------
    def shading(self, engine: Any, draw: Any) -> int:
        """Each model's shading stage and fog into the frame, where the G-buffer's surface is the one seen."""
        layout = self.layout
        assert layout is not None
        ctx = engine.ctx
        gbuffer = engine.target(GBUFFER)
        stencil, samples = self._frame_path
        defines = self._frame_defines(engine)
        if engine.linear_output:
            defines["LINEAR_OUTPUT"] = True
        engine.default_gl_state()
        # The full-screen triangle lies at window depth 0.5: the default depth test ("less") would keep only
        # surfaces behind that depth (all but the nearest under a perspective camera, none under an
        # orthographic one, whose depth is linear).  Where the G-buffer's surface is seen is decided by the
        # stencil marks, the G-buffer depth written by the fragment, or the edge blending below, never by it.
        if stencil:  # the depth pass marked the samples where the G-buffer's surface won
            defines["STENCIL_MARKED"] = True
            engine.apply_gl_state(*_SHADE_MARKED)
        elif samples <= 1:  # where the G-buffer's depth is the frame's
            defines["FRAG_DEPTH"] = True
            engine.apply_gl_state(*_SHADE_EQUAL_DEPTH)
        else:  # edges blend their samples' mean over the samples no surface covers
            engine.apply_gl_state(*_SHADE_EDGES)
        extra: dict[str, Any] = {}
        if samples > 1:
            extra["u_pixels"] = engine.target(_PIXELS.name).texture("pixel")
            if layout.has_lbuffer:
                lights = engine.target(_LIGHTS)
                for name in layout.light_layers:
                    for k in range(samples):
                        extra[f"u_{name}_s{k}"] = lights.texture(f"{name}_s{k}")
        key = ("shading", layout.key, samples, tuple(sorted(defines.items())))
        prog = self._program(engine, key, *shading_program(layout, samples, defines))
        try:
            self._bind_buffers(engine, prog, gbuffer, ambient=True, extra=extra)
            for name, value in self._fog_uniforms.items():
                u = prog.get(name, None)
                if u is not None:
                    u.write(np.asarray(value, np.float32)[: u.array_length * u.dimension].tobytes())
            vao, _ = self._vao(engine, prog, FULLSCREEN, 1)
            vao.render(ctx.TRIANGLES, instances=1)
        finally:
            engine.apply_gl_state(_NO_STENCIL)
            if stencil:  # the marks go again: the stencil is as the frame had it (only those bits cleared)
                engine.apply_gl_state(*_CLEAR_MARKS)
                clear_stencil_value(engine.raw, 0)
            engine.default_gl_state()
        engine.count(1, 0)
        return 1

    # -- reporting -----------------------------------------------------------------------------------
    def describe(self, size: tuple[int, int] | None = None) -> str:
        """The pipeline's passes and the buffer layout of the last frame (memory at ``size``, default the engine's)."""
        engine = self.engine
        layout = self.layout or BufferLayout([PHONG])
        size = tuple(engine.size) if size is None else size
        samples = engine.samples
        lines = ["deferred pipeline: geometry -> lighting -> shading -> compositing (forward, transparent, overlay)"]
        lines.append(layout.describe(size, samples))
        return "\n".join(lines)

    def memory(self, size: tuple[int, int] | None = None, samples: int | None = None) -> int:
        """Bytes of the G-buffer and L-buffer of the last frame's layout at ``size`` (default: the engine's)."""
        layout = self.layout or BufferLayout([PHONG])
        return layout.memory(tuple(self.engine.size) if size is None else size,
                             self.engine.samples if samples is None else samples)  # fmt: skip

    def release(self) -> None:
        for vao, buf, _ in self._vaos.values():
            vao.release()
            buf.release()
        self._vaos.clear()
        for vbo, ibo in self._meshes.values():
            vbo.release()
            ibo.release()
        self._meshes.clear()
        self._release_fbos()
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()


#: The per-pixel centre depth and edge flag of a multisampled G-buffer, and the lights of its edge samples.
_PIXELS = Target("deferred.pixels", colors=("pixel",), formats=("rg32f",), depth=True, relative="enclosing")
_LIGHTS = "deferred.lights"


# The GL state of the deferred passes (made once: state attributes are components, cheap to apply, not to make).
_LIGHTS_STATE = (DepthMask(False), Blend(True, "one", "one"), DepthClamp(True))
_PROXY_STATE = {(fullscreen, tested): (CullFace("none" if fullscreen else "front"), DepthTest(tested, "gequal"))
                for fullscreen in (False, True) for tested in (False, True)}  # fmt: skip
_ALWAYS = DepthTest(True, "always")
_DEPTH_STATE = (ColorMask(False, False, False, False), DepthMask(True), DepthTest(True, "less"))
_MARK_STATE = (StencilTest(True, "always", _WON, _WON), StencilOp("keep", "keep", "replace", _WON))
_SHADE_MARKED = (DepthMask(False), DepthTest(False), StencilTest(True, "equal", _WON, _WON))
_SHADE_EQUAL_DEPTH = (DepthMask(False), DepthTest(True, "equal"))
_SHADE_EDGES = (DepthMask(False), DepthTest(False), Blend(True, "one", "one_minus_src_alpha"))
_NO_STENCIL = StencilTest(False)
_CLEAR_MARKS = (ScissorTest(enabled=False), StencilOp(write_mask=_WON))


def _mask_sample(engine: Any, prog: Any, k: int | None) -> None:
    """Let only sample ``k`` be written and tell ``prog`` which sample it reads (None: one draw, every sample)."""
    engine.sample_mask(k)
    if k is None:
        u = prog.get("u_sample", None)
        if u is not None:
            u.value = 0
        return
    prog["u_sample"].value = k


def current_samples(engine: Any) -> int:
    """The sample count of the framebuffer the engine draws into now (0 or 1: one sample)."""
    raw = engine.raw
    if not raw.available:
        return 0
    value = ctypes.c_int(0)
    raw.glGetIntegerv(GL_SAMPLES, ctypes.byref(value))
    return int(value.value) if value.value > 1 else 0
