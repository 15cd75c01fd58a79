"""Snapshots of the OpenGL raster state: capture what is set, compare, and put it back.

A renderer that shares a context with others "sets the state it needs and
restores the state it found" (DESIGN.md, integration rule 4).
:func:`capture_state` reads the state that decides what a draw call does to
the framebuffer -- the bound framebuffers, viewport and scissor box, every
capability switch (depth, blend, cull, stencil, scissor, polygon offset, depth
clamp, clip distances...), depth/blend/stencil functions and write masks,
face culling, polygon mode and offset, line width, depth range -- with
``glGet*`` calls; :meth:`GLStateSnapshot.restore` sets it back and
:meth:`GLStateSnapshot.diff` names what differs.  Bindings of objects that
every draw call binds itself (program, vertex array, buffers, textures) are
not part of it.

moderngl exposes no ``glGet``; the calls go through :class:`~.context.RawGL`
(the process's libOpenGL/libGL, which GLVND dispatches to the current context).
"""

from __future__ import annotations

import contextlib
import ctypes
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from .context import GLError, RawGL
from .glenum import (
    GL_ATTACHMENT_OBJECT_TYPE,
    GL_ATTACHMENT_STENCIL_SIZE,
    GL_BACK,
    GL_BLEND,
    GL_BLEND_COLOR,
    GL_BLEND_DST_ALPHA,
    GL_BLEND_DST_RGB,
    GL_BLEND_EQUATION_ALPHA,
    GL_BLEND_EQUATION_RGB,
    GL_BLEND_SRC_ALPHA,
    GL_BLEND_SRC_RGB,
    GL_CLIP_DISTANCE0,
    GL_COLOR_LOGIC_OP,
    GL_COLOR_WRITEMASK,
    GL_CULL_FACE,
    GL_CULL_FACE_MODE,
    GL_DEPTH_CLAMP,
    GL_DEPTH_FUNC,
    GL_DEPTH_RANGE,
    GL_DEPTH_TEST,
    GL_DEPTH_WRITEMASK,
    GL_DITHER,
    GL_DRAW_FRAMEBUFFER,
    GL_DRAW_FRAMEBUFFER_BINDING,
    GL_FRAMEBUFFER_SRGB,
    GL_FRONT,
    GL_FRONT_AND_BACK,
    GL_FRONT_FACE,
    GL_LINE_WIDTH,
    GL_MULTISAMPLE,
    GL_PACK_ALIGNMENT,
    GL_POINT_SIZE,
    GL_POLYGON_MODE,
    GL_POLYGON_OFFSET_FACTOR,
    GL_POLYGON_OFFSET_FILL,
    GL_POLYGON_OFFSET_LINE,
    GL_POLYGON_OFFSET_POINT,
    GL_POLYGON_OFFSET_UNITS,
    GL_PRIMITIVE_RESTART,
    GL_PROGRAM_POINT_SIZE,
    GL_PROVOKING_VERTEX,
    GL_RASTERIZER_DISCARD,
    GL_READ_FRAMEBUFFER,
    GL_READ_FRAMEBUFFER_BINDING,
    GL_SAMPLE_ALPHA_TO_COVERAGE,
    GL_SAMPLE_COVERAGE,
    GL_SAMPLE_COVERAGE_INVERT,
    GL_SAMPLE_COVERAGE_VALUE,
    GL_SCISSOR_BOX,
    GL_SCISSOR_TEST,
    GL_STENCIL,
    GL_STENCIL_ATTACHMENT,
    GL_STENCIL_BACK_FAIL,
    GL_STENCIL_BACK_FUNC,
    GL_STENCIL_BACK_PASS_DEPTH_FAIL,
    GL_STENCIL_BACK_PASS_DEPTH_PASS,
    GL_STENCIL_BACK_REF,
    GL_STENCIL_BACK_VALUE_MASK,
    GL_STENCIL_BACK_WRITEMASK,
    GL_STENCIL_BUFFER_BIT,
    GL_STENCIL_FAIL,
    GL_STENCIL_FUNC,
    GL_STENCIL_INDEX,
    GL_STENCIL_PASS_DEPTH_FAIL,
    GL_STENCIL_PASS_DEPTH_PASS,
    GL_STENCIL_REF,
    GL_STENCIL_TEST,
    GL_STENCIL_VALUE_MASK,
    GL_STENCIL_WRITEMASK,
    GL_UNSIGNED_BYTE,
    GL_VIEWPORT,
)

__all__ = ["GLStateSnapshot", "capture_state", "preserved_state", "read_stencil", "stencil_bits"]

# capabilities (glIsEnabled / glEnable / glDisable)
_CAPS = {
    "blend": GL_BLEND,
    "cull_face": GL_CULL_FACE,
    "depth_test": GL_DEPTH_TEST,
    "stencil_test": GL_STENCIL_TEST,
    "scissor_test": GL_SCISSOR_TEST,
    "polygon_offset_fill": GL_POLYGON_OFFSET_FILL,
    "polygon_offset_line": GL_POLYGON_OFFSET_LINE,
    "polygon_offset_point": GL_POLYGON_OFFSET_POINT,
    "depth_clamp": GL_DEPTH_CLAMP,
    "multisample": GL_MULTISAMPLE,
    "sample_alpha_to_coverage": GL_SAMPLE_ALPHA_TO_COVERAGE,
    "sample_coverage": GL_SAMPLE_COVERAGE,
    "program_point_size": GL_PROGRAM_POINT_SIZE,
    "framebuffer_srgb": GL_FRAMEBUFFER_SRGB,
    "rasterizer_discard": GL_RASTERIZER_DISCARD,
    "dither": GL_DITHER,
    "color_logic_op": GL_COLOR_LOGIC_OP,
    "primitive_restart": GL_PRIMITIVE_RESTART,
    **{f"clip_distance{i}": GL_CLIP_DISTANCE0 + i for i in range(8)},
}
# integer states: name -> (enum, count)
_INTS = {
    "draw_framebuffer": (GL_DRAW_FRAMEBUFFER_BINDING, 1),
    "read_framebuffer": (GL_READ_FRAMEBUFFER_BINDING, 1),
    "viewport": (GL_VIEWPORT, 4),
    "scissor_box": (GL_SCISSOR_BOX, 4),
    "depth_func": (GL_DEPTH_FUNC, 1),
    "blend_src_rgb": (GL_BLEND_SRC_RGB, 1),
    "blend_dst_rgb": (GL_BLEND_DST_RGB, 1),
    "blend_src_alpha": (GL_BLEND_SRC_ALPHA, 1),
    "blend_dst_alpha": (GL_BLEND_DST_ALPHA, 1),
    "blend_equation_rgb": (GL_BLEND_EQUATION_RGB, 1),
    "blend_equation_alpha": (GL_BLEND_EQUATION_ALPHA, 1),
    "cull_face_mode": (GL_CULL_FACE_MODE, 1),
    "front_face": (GL_FRONT_FACE, 1),
    "polygon_mode": (GL_POLYGON_MODE, 2),
    "stencil_func": (GL_STENCIL_FUNC, 1),
    "stencil_ref": (GL_STENCIL_REF, 1),
    "stencil_value_mask": (GL_STENCIL_VALUE_MASK, 1),
    "stencil_fail": (GL_STENCIL_FAIL, 1),
    "stencil_pass_depth_fail": (GL_STENCIL_PASS_DEPTH_FAIL, 1),
    "stencil_pass_depth_pass": (GL_STENCIL_PASS_DEPTH_PASS, 1),
    "stencil_writemask": (GL_STENCIL_WRITEMASK, 1),
    "stencil_back_func": (GL_STENCIL_BACK_FUNC, 1),
    "stencil_back_ref": (GL_STENCIL_BACK_REF, 1),
    "stencil_back_value_mask": (GL_STENCIL_BACK_VALUE_MASK, 1),
    "stencil_back_fail": (GL_STENCIL_BACK_FAIL, 1),
    "stencil_back_pass_depth_fail": (GL_STENCIL_BACK_PASS_DEPTH_FAIL, 1),
    "stencil_back_pass_depth_pass": (GL_STENCIL_BACK_PASS_DEPTH_PASS, 1),
    "stencil_back_writemask": (GL_STENCIL_BACK_WRITEMASK, 1),
    "provoking_vertex": (GL_PROVOKING_VERTEX, 1),
}
_FLOATS = {
    "blend_color": (GL_BLEND_COLOR, 4),
    "polygon_offset_factor": (GL_POLYGON_OFFSET_FACTOR, 1),
    "polygon_offset_units": (GL_POLYGON_OFFSET_UNITS, 1),
    "line_width": (GL_LINE_WIDTH, 1),
    "point_size": (GL_POINT_SIZE, 1),
    "depth_range": (GL_DEPTH_RANGE, 2),
    "sample_coverage_value": (GL_SAMPLE_COVERAGE_VALUE, 1),
}
_BOOLS = {
    "depth_writemask": (GL_DEPTH_WRITEMASK, 1),
    "color_writemask": (GL_COLOR_WRITEMASK, 4),
    "sample_coverage_invert": (GL_SAMPLE_COVERAGE_INVERT, 1),
}


_RAW: RawGL | None = None


def _gl() -> RawGL:
    """The raw GL entry points (loaded once), or GLError when libOpenGL/libGL is missing."""
    global _RAW
    if _RAW is None:
        _RAW = RawGL()
    if not _RAW.available:
        raise GLError("GL state snapshots need libOpenGL/libGL (glGet*), which was not found")
    return _RAW


def _read(getter: Any, enum: int, count: int, ctype: Any) -> Any:
    buf = (ctype * 4)()
    getter(enum, buf)
    values = tuple(buf[:count])
    return values[0] if count == 1 else values


class GLStateSnapshot(Mapping):
    """The raster state of the current context at one moment: a read-only mapping name -> value.

    ``restore()`` makes it current again; ``diff(other)`` lists ``(name,
    mine, theirs)`` for every entry that differs.  ``framebuffer`` is the
    moderngl framebuffer that was bound, when the caller named it: restoring
    binds it through moderngl, so moderngl's own idea of the bound framebuffer
    stays right.
    """

    def __init__(self, values: dict[str, Any], framebuffer: Any = None) -> None:
        self._values = values
        self.framebuffer = framebuffer

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def replace(self, **values: Any) -> GLStateSnapshot:
        """A copy with some entries changed (e.g. a deliberately unusual state to start a test from)."""
        unknown = sorted(set(values) - set(self._values))
        if unknown:
            raise KeyError(f"GLStateSnapshot.replace: unknown state {unknown}; known: {sorted(self._values)}")
        return GLStateSnapshot({**self._values, **values}, self.framebuffer)

    def diff(self, other: Mapping[str, Any]) -> list[tuple[str, Any, Any]]:
        """``(name, this value, other value)`` for every state that differs (floats compared to 1e-6)."""
        out = []
        for name, mine in self._values.items():
            theirs = other[name]
            if not np.allclose(np.asarray(mine, dtype=np.float64), np.asarray(theirs, dtype=np.float64), atol=1e-6):
                out.append((name, mine, theirs))
        return out

    def restore(self) -> None:
        """Set the current context's state to this snapshot."""
        gl = _gl()
        v = self._values
        fbo = self.framebuffer
        if fbo is not None and getattr(fbo, "glo", None) == v["draw_framebuffer"]:
            fbo.use()  # through moderngl, which remembers the bound framebuffer (it sets masks: restored below)
        gl.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, v["draw_framebuffer"])
        gl.glBindFramebuffer(GL_READ_FRAMEBUFFER, v["read_framebuffer"])
        for name, enum in _CAPS.items():
            (gl.glEnable if v[name] else gl.glDisable)(enum)
        gl.glViewport(*v["viewport"])
        gl.glScissor(*v["scissor_box"])
        gl.glDepthFunc(v["depth_func"])
        gl.glDepthMask(1 if v["depth_writemask"] else 0)
        gl.glColorMask(*(1 if c else 0 for c in v["color_writemask"]))
        gl.glBlendFuncSeparate(v["blend_src_rgb"], v["blend_dst_rgb"], v["blend_src_alpha"], v["blend_dst_alpha"])
        gl.glBlendEquationSeparate(v["blend_equation_rgb"], v["blend_equation_alpha"])
        gl.glBlendColor(*v["blend_color"])
        gl.glCullFace(v["cull_face_mode"])
        gl.glFrontFace(v["front_face"])
        gl.glPolygonMode(GL_FRONT_AND_BACK, v["polygon_mode"][0])
        gl.glPolygonOffset(v["polygon_offset_factor"], v["polygon_offset_units"])
        gl.glLineWidth(v["line_width"])
        gl.glPointSize(v["point_size"])
        gl.glDepthRange(*v["depth_range"])
        gl.glSampleCoverage(v["sample_coverage_value"], 1 if v["sample_coverage_invert"] else 0)
        gl.glProvokingVertex(v["provoking_vertex"])
        for face, prefix in ((GL_FRONT, "stencil"), (GL_BACK, "stencil_back")):
            gl.glStencilFuncSeparate(face, v[f"{prefix}_func"], v[f"{prefix}_ref"], v[f"{prefix}_value_mask"])
            gl.glStencilOpSeparate(
                face, v[f"{prefix}_fail"], v[f"{prefix}_pass_depth_fail"], v[f"{prefix}_pass_depth_pass"]
            )
            gl.glStencilMaskSeparate(face, v[f"{prefix}_writemask"])

    def __repr__(self) -> str:
        return f"GLStateSnapshot({len(self._values)} states, framebuffer {self._values['draw_framebuffer']})"


def capture_state(framebuffer: Any = None) -> GLStateSnapshot:
    """The raster state of the current context (see the module docstring for what it holds).

    ``framebuffer``: the moderngl framebuffer the caller knows to be bound (for :meth:`~GLStateSnapshot.restore`).
    """
    gl = _gl()
    values: dict[str, Any] = {name: bool(gl.glIsEnabled(enum)) for name, enum in _CAPS.items()}
    for name, (enum, count) in _INTS.items():
        value = _read(gl.glGetIntegerv, enum, count, ctypes.c_int)
        values[name] = value & 0xFFFFFFFF if name.endswith(("value_mask", "writemask")) else value
    for name, (enum, count) in _FLOATS.items():
        values[name] = _read(gl.glGetFloatv, enum, count, ctypes.c_float)
    for name, (enum, count) in _BOOLS.items():
        got = _read(gl.glGetBooleanv, enum, count, ctypes.c_ubyte)
        values[name] = tuple(bool(x) for x in got) if count > 1 else bool(got)
    return GLStateSnapshot(values, framebuffer)


@contextlib.contextmanager
def preserved_state(framebuffer: Any = None) -> Iterator[GLStateSnapshot]:
    """Run a block and put the raster state back as it was (integration rule 4, for code that changes state)."""
    saved = capture_state(framebuffer)
    try:
        yield saved
    finally:
        saved.restore()


def stencil_bits() -> int:
    """Stencil bits of the bound draw framebuffer (0: it has no stencil buffer)."""
    gl = _gl()
    draw = _read(gl.glGetIntegerv, _INTS["draw_framebuffer"][0], 1, ctypes.c_int)
    if draw == 0:
        attachment = GL_STENCIL
    else:
        kind = ctypes.c_int(0)
        gl.glGetFramebufferAttachmentParameteriv(
            GL_DRAW_FRAMEBUFFER, GL_STENCIL_ATTACHMENT, GL_ATTACHMENT_OBJECT_TYPE, ctypes.byref(kind)
        )
        if kind.value == 0:  # GL_NONE: nothing attached
            return 0
        attachment = GL_STENCIL_ATTACHMENT
    bits = ctypes.c_int(0)
    gl.glGetFramebufferAttachmentParameteriv(
        GL_DRAW_FRAMEBUFFER, attachment, GL_ATTACHMENT_STENCIL_SIZE, ctypes.byref(bits)
    )
    return int(bits.value)


def write_stencil(framebuffer: Any, stencil: np.ndarray, cell: int) -> None:
    """Write ``stencil`` ((H, W) values, top row first) into ``framebuffer``'s stencil buffer, one value per
    ``cell`` x ``cell`` block (its top-left pixel's), with scissored clears; the raster state is put back after."""
    gl = _gl()
    h = stencil.shape[0]
    with preserved_state(framebuffer):
        gl.glEnable(GL_SCISSOR_TEST)
        gl.glStencilMaskSeparate(GL_FRONT_AND_BACK, 0xFF)
        for y in range(0, h, cell):
            for x in range(0, stencil.shape[1], cell):
                gl.glScissor(x, h - y - cell, cell, cell)
                gl.glClearStencil(int(stencil[y, x]))
                gl.glClear(GL_STENCIL_BUFFER_BIT)


def read_stencil(framebuffer: Any, size: tuple[int, int]) -> np.ndarray:
    """The stencil buffer of ``framebuffer`` (a single-sample moderngl framebuffer) as (H, W) uint8, top row first.

    The read binding and pack alignment are restored afterwards.
    """
    gl = _gl()
    w, h = size
    out = np.zeros((h, w), np.uint8)
    previous = _read(gl.glGetIntegerv, _INTS["read_framebuffer"][0], 1, ctypes.c_int)
    align = _read(gl.glGetIntegerv, GL_PACK_ALIGNMENT, 1, ctypes.c_int)
    gl.glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer.glo)
    gl.glPixelStorei(GL_PACK_ALIGNMENT, 1)
    gl.glReadPixels(0, 0, w, h, GL_STENCIL_INDEX, GL_UNSIGNED_BYTE, out.ctypes.data)
    gl.glPixelStorei(GL_PACK_ALIGNMENT, align)
    gl.glBindFramebuffer(GL_READ_FRAMEBUFFER, previous)
    return out[::-1].copy()
