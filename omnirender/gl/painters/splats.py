"""``om.GaussianSplats`` in GL: the reference rasteriser's method, sorted on the GPU, composited by depth.

The painter records one transparent draw item per splat set (kind
``"splats"``); its geometry (:class:`SplatGeometry`) holds the splat data as
two float textures, uploaded once per version of the shape.  The drawer
(:func:`draw_splats`), met among the transparent items back to front:

1. orders the splats back to front for the pass's model-view matrix -- on the
   GPU with compute shaders (:mod:`.splat_sort`), else with numpy -- only
   when the view or the splats changed;
2. draws one instanced quad per splat (a 4-vertex strip, the sorted index as
   the instance attribute); the vertex shader projects the splat's 3D
   covariance to a 2D screen ellipse (EWA: ``J W Sigma W^T J^T`` + 0.3 px^2,
   the paper's low-pass dilation), sizes the quad to 3 sigma of its larger
   axis and evaluates the spherical-harmonics colour for the view direction
   (:mod:`.splats_glsl`, the constants of ``shapes/_sh.py``); the fragment
   shader writes ``alpha = min(0.99, opacity * exp(-0.5 d^T Sigma2D^-1 d))``
   premultiplied, discarding below 1/255;
3. blends ``(one, one_minus_src_alpha)`` with the depth test against what is
   already drawn (opaque shapes hide splats behind them) and without depth
   writes (splats in front of shapes blend over them).

Colours are the trainer's display values: in a display (8-bit) target the
splats blend in display space as the trainer did; in a linear target (HDR,
post-processing, deferred) they are decoded and blend in linear light.
Clip planes do not cut splats (documented in docs/DESIGN.md).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...core.handler import ShapePainter, default_for
from ...shapes import GaussianSplats
from ..engine.attributes import Blend, CullFace, DepthMask, DepthTest
from ..engine.geometry import Geometry
from ..engine.layout import ROW
from ..engine.resources import gpu_call
from ..glengine import GLEngine
from .splat_sort import SortPrograms, compute_available, sorter_for
from .splats_glsl import SPLAT_FRAGMENT, SPLAT_VERTEX

__all__ = ["SplatGeometry", "SplatPainter", "draw_splats", "sort_method"]

#: texels per row of the splat-data textures (at most the driver's limit)
TEXTURE_WIDTH = 4096

_CORNERS = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], dtype=np.float32)


class SplatGeometry(Geometry):
    """The data of one version of a ``GaussianSplats``: CPU arrays for the textures, uploaded on first draw."""

    __slots__ = ("splat_count", "degree", "width", "geom_data", "sh_data", "centers", "textures", "sorter", "vaos")

    def __init__(self, splats: GaussianSplats, label: str, max_size: int) -> None:
        a = splats.checked()
        box = splats.bounds(3.0)
        lo, hi = (np.zeros(3), np.zeros(3)) if box is None else box
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        super().__init__("points", corners, label=label)
        n = len(a.positions)
        k = (a.sh_degree + 1) ** 2
        width = min(TEXTURE_WIDTH, max_size)
        rows = max(1, -(-3 * n // width))
        sh_rows = max(1, -(-k * n // width))
        if max(rows, sh_rows) > max_size:
            raise ValueError(
                f"GaussianSplats in {label}: {n} splats of SH degree {a.sh_degree} need {max(rows, sh_rows)} texture "
                f"rows of {width}; the driver allows {max_size}: split the splats into several shapes"
            )
        cov = splats.covariances()
        g = np.zeros((rows * width, 4), dtype=np.float32)
        v = g[: 3 * n].reshape(n, 3, 4)
        v[:, 0, :3] = a.positions
        v[:, 0, 3] = a.opacities
        v[:, 1] = np.stack([cov[:, 0, 0], cov[:, 0, 1], cov[:, 0, 2], cov[:, 1, 1]], axis=1)
        v[:, 2, 0] = cov[:, 1, 2]
        v[:, 2, 1] = cov[:, 2, 2]
        sh = np.zeros((sh_rows * width, 4), dtype=np.float16)
        sh[: k * n, :3] = a.sh.reshape(n * k, 3)
        self.splat_count = n
        self.degree = a.sh_degree
        self.width = width
        self.geom_data = g
        self.sh_data = sh
        self.centers = np.ascontiguousarray(a.positions, dtype=np.float32)
        self.textures: tuple[Any, Any, Any] | None = None  # geometry texture, SH texture, quad corners
        self.sorter: Any = None
        self.vaos: dict[tuple[int, int], Any] = {}

    def upload_splats(self, ctx: Any) -> tuple[Any, Any, Any]:
        """The two data textures and the corner buffer (made once)."""
        if self.textures is None:
            w = self.width
            geom = gpu_call(
                ctx.texture, (w, len(self.geom_data) // w), 4, self.geom_data.tobytes(), dtype="f4",
                what=f"splats of {self.label}",
            )  # fmt: skip
            sh = gpu_call(
                ctx.texture, (w, len(self.sh_data) // w), 4, self.sh_data.tobytes(), dtype="f2",
                what=f"splat colours of {self.label}",
            )  # fmt: skip
            for t in (geom, sh):
                t.filter = (ctx.NEAREST, ctx.NEAREST)
                t.repeat_x = t.repeat_y = False
            corners = gpu_call(ctx.buffer, _CORNERS.tobytes(), what=f"splat quad of {self.label}")
            self.textures = (geom, sh, corners)
        return self.textures

    def release(self) -> None:
        super().release()
        for vao in self.vaos.values():
            vao.release()
        self.vaos = {}
        if self.sorter is not None:
            self.sorter.release()
            self.sorter = None
        if self.textures is not None:
            for t in self.textures:
                t.release()
            self.textures = None


@default_for(GLEngine)
class SplatPainter(ShapePainter):
    """Gaussian splats: one transparent item drawn by :func:`draw_splats` (sorted, EWA-projected quads)."""

    __slots__ = ()
    service = "gl.paint"
    target = GaussianSplats

    def exec(self, shape: GaussianSplats, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            geom = SplatGeometry(shape, f"GaussianSplats in {engine.node_path or '/'}", engine.max_texture_size)
            engine.geometry_cache.put(shape, geom)
        engine.submit(geom, None, kind="splats", transparent=True)


#: depth-tested against what is drawn, no depth writes, premultiplied "over", both faces
_STATE = (DepthTest(True, "less"), DepthMask(False), Blend(True, "one", "one_minus_src_alpha"), CullFace("none"))

#: depth-only passes: depth written where a splat's alpha reaches the pass's cutoff, the colour kept by blending
#: (zero, one) -- not by a colour mask, which would outlive the pass for the next custom drawer
_DEPTH_STATE = (DepthTest(True, "less"), DepthMask(True), Blend(True, "zero", "one"), CullFace("none"))

#: per engine: the compute programs of the GPU sort (None where compute shaders are missing)
_SORT_PROGRAMS: weakref.WeakKeyDictionary[Any, Any] = weakref.WeakKeyDictionary()


def sort_method(engine: GLEngine) -> str:
    """How ``engine`` orders splats: ``"gpu bitonic"`` (compute shaders) or ``"numpy"`` (the fallback)."""
    return "gpu bitonic" if _sort_programs(engine) is not None else "numpy"


def _sort_programs(engine: GLEngine) -> Any:
    if engine not in _SORT_PROGRAMS:
        programs = None
        if compute_available(engine.ctx):
            try:
                programs = SortPrograms(engine.ctx)
            except Exception:  # a driver that reports 4.3 but fails to build them: the fallback still draws
                programs = None
        _SORT_PROGRAMS[engine] = programs
    return _SORT_PROGRAMS[engine]


def draw_splats(engine: GLEngine, items: list, state: Any) -> int:
    """The drawer for ``"splats"`` items."""
    ctx = engine.ctx
    if not engine.programs.registered("splats"):
        engine.programs.register("splats", SPLAT_VERTEX, SPLAT_FRAGMENT)
    shading = engine.pass_shading
    if shading.get("DEPTH_ONLY"):
        # the pass's state does not reach custom drawers: keep the colour, write the depth of the denser splats
        features: tuple = (("DEPTH_ONLY", True), ("PASS_ALPHA_CUTOFF", float(shading.get("PASS_ALPHA_CUTOFF", 0.5))))
        engine.apply_gl_state(*_DEPTH_STATE)
    else:
        features = (("LINEAR_OUTPUT", True),) if engine.linear_output else ()
        engine.apply_gl_state(*_STATE)
    prog = engine.programs.get("splats", features)
    view, proj = engine.frame_view, engine.frame_projection
    ortho = engine.frame_orthographic
    viewport = tuple(float(v) for v in ctx.viewport)  # the pass's rectangle (a stereo eye's half, a tile)
    near = (proj[2, 3] + 1.0) / proj[2, 2] if ortho else proj[2, 3] / (proj[2, 2] - 1.0)
    calls = 0
    for item in items:
        geom: SplatGeometry = item.geometry
        if geom.splat_count == 0:
            continue
        tex_geom, tex_sh, corners = geom.upload_splats(ctx)
        if geom.sorter is None:
            geom.sorter = sorter_for(ctx, geom.centers, geom.label, _sort_programs(engine))
        model = item.row[ROW.slice("model")].reshape(4, 4).T.astype(np.float64)
        mv = view @ model
        order = geom.sorter.order(mv, tex_geom, geom.width)
        inv = np.linalg.inv(mv)
        if ortho:
            eye = np.append(inv[:3, :3] @ np.array([0.0, 0.0, -1.0]), 0.0)
        else:
            eye = inv @ np.array([0.0, 0.0, 0.0, 1.0])
            eye = eye / eye[3]
        uniforms = {
            "u_mv": mv.T.astype(np.float32).tobytes(),
            "u_proj": proj.T.astype(np.float32).tobytes(),
            "u_viewport": viewport,
            "u_eye": tuple(float(x) for x in eye),
            "u_near": float(near),
            "u_width": int(geom.width),
            "u_degree": int(geom.degree),
            "u_sh_count": int((geom.degree + 1) ** 2),
            "u_geom": 0,
            "u_sh": 1,
        }
        for name, value in uniforms.items():
            member = prog.get(name, None)  # a depth-only program has no colour uniforms
            if member is None:
                continue
            if isinstance(value, bytes):
                member.write(value)
            else:
                member.value = value
        tex_geom.use(0)
        tex_sh.use(1)
        key = (id(prog), id(order))
        vao = geom.vaos.get(key)
        if vao is None:
            vao = geom.vaos[key] = ctx.vertex_array(prog, [(corners, "2f", "in_corner"), (order, "u/i", "in_splat")])
        vao.render(ctx.TRIANGLE_STRIP, vertices=4, instances=geom.splat_count)
        calls += 1
    return calls


GLEngine.register_drawer("splats", draw_splats)
