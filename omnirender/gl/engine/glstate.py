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

__all__ = ["GLStateSnapshot", "capture_state", "preserved_state", "read_stencil", "stencil_bits"]

# capabilities (glIsEnabled / glEnable / glDisable)
_CAPS = {
    "blend": 0x0BE2,
    "cull_face": 0x0B44,
    "depth_test": 0x0B71,
    "stencil_test": 0x0B90,
    "scissor_test": 0x0C11,
    "polygon_offset_fill": 0x8037,
    "polygon_offset_line": 0x2A02,
    "polygon_offset_point": 0x2A01,
    "depth_clamp": 0x864F,
    "multisample": 0x809D,
    "sample_alpha_to_coverage": 0x809E,
    "sample_coverage": 0x80A0,
    "program_point_size": 0x8642,
    "framebuffer_srgb": 0x8DB9,
    "rasterizer_discard": 0x8C89,
    "dither": 0x0BD0,
    "color_logic_op": 0x0BF2,
    "primitive_restart": 0x8F9D,
    **{f"clip_distance{i}": 0x3000 + i for i in range(8)},
}
# integer states: name -> (enum, count)
_INTS = {
    "draw_framebuffer": (0x8CA6, 1),
    "read_framebuffer": (0x8CAA, 1),
    "viewport": (0x0BA2, 4),
    "scissor_box": (0x0C10, 4),
    "depth_func": (0x0B74, 1),
    "blend_src_rgb": (0x80C9, 1),
    "blend_dst_rgb": (0x80C8, 1),
    "blend_src_alpha": (0x80CB, 1),
    "blend_dst_alpha": (0x80CA, 1),
    "blend_equation_rgb": (0x8009, 1),
    "blend_equation_alpha": (0x883D, 1),
    "cull_face_mode": (0x0B45, 1),
    "front_face": (0x0B46, 1),
    "polygon_mode": (0x0B40, 2),
    "stencil_func": (0x0B92, 1),
    "stencil_ref": (0x0B97, 1),
    "stencil_value_mask": (0x0B93, 1),
    "stencil_fail": (0x0B94, 1),
    "stencil_pass_depth_fail": (0x0B95, 1),
    "stencil_pass_depth_pass": (0x0B96, 1),
    "stencil_writemask": (0x0B98, 1),
    "stencil_back_func": (0x8800, 1),
    "stencil_back_ref": (0x8CA3, 1),
    "stencil_back_value_mask": (0x8CA4, 1),
    "stencil_back_fail": (0x8801, 1),
    "stencil_back_pass_depth_fail": (0x8802, 1),
    "stencil_back_pass_depth_pass": (0x8803, 1),
    "stencil_back_writemask": (0x8CA5, 1),
    "provoking_vertex": (0x8E4F, 1),
}
_FLOATS = {
    "blend_color": (0x8005, 4),
    "polygon_offset_factor": (0x8038, 1),
    "polygon_offset_units": (0x2A00, 1),
    "line_width": (0x0B21, 1),
    "point_size": (0x0B11, 1),
    "depth_range": (0x0B70, 2),
    "sample_coverage_value": (0x80AA, 1),
}
_BOOLS = {"depth_writemask": (0x0B72, 1), "color_writemask": (0x0C23, 4), "sample_coverage_invert": (0x80AB, 1)}

_GL_FRAMEBUFFER = 0x8D40
_GL_DRAW_FRAMEBUFFER = 0x8CA9
_GL_READ_FRAMEBUFFER = 0x8CA8
_GL_FRONT, _GL_BACK, _GL_FRONT_AND_BACK = 0x0404, 0x0405, 0x0408
_GL_STENCIL_INDEX, _GL_UNSIGNED_BYTE = 0x1901, 0x1401
_GL_STENCIL = 0x1802
_GL_ATTACHMENT_STENCIL_SIZE = 0x8217
_GL_ATTACHMENT_OBJECT_TYPE = 0x8CD0
_GL_STENCIL_ATTACHMENT = 0x8D20
_GL_DEPTH_STENCIL_ATTACHMENT = 0x821A
_GL_PACK_ALIGNMENT = 0x0D05

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
        gl.glBindFramebuffer(_GL_DRAW_FRAMEBUFFER, v["draw_framebuffer"])
        gl.glBindFramebuffer(_GL_READ_FRAMEBUFFER, v["read_framebuffer"])
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
        gl.glPolygonMode(_GL_FRONT_AND_BACK, v["polygon_mode"][0])
        gl.glPolygonOffset(v["polygon_offset_factor"], v["polygon_offset_units"])
        gl.glLineWidth(v["line_width"])
        gl.glPointSize(v["point_size"])
        gl.glDepthRange(*v["depth_range"])
        gl.glSampleCoverage(v["sample_coverage_value"], 1 if v["sample_coverage_invert"] else 0)
        gl.glProvokingVertex(v["provoking_vertex"])
        for face, prefix in ((_GL_FRONT, "stencil"), (_GL_BACK, "stencil_back")):
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
        attachment = _GL_STENCIL
    else:
        kind = ctypes.c_int(0)
        gl.glGetFramebufferAttachmentParameteriv(
            _GL_DRAW_FRAMEBUFFER, _GL_STENCIL_ATTACHMENT, _GL_ATTACHMENT_OBJECT_TYPE, ctypes.byref(kind)
        )
        if kind.value == 0:  # GL_NONE: nothing attached
            return 0
        attachment = _GL_STENCIL_ATTACHMENT
    bits = ctypes.c_int(0)
    gl.glGetFramebufferAttachmentParameteriv(
        _GL_DRAW_FRAMEBUFFER, attachment, _GL_ATTACHMENT_STENCIL_SIZE, ctypes.byref(bits)
    )
    return int(bits.value)


def read_stencil(framebuffer: Any, size: tuple[int, int]) -> np.ndarray:
    """The stencil buffer of ``framebuffer`` (a single-sample moderngl framebuffer) as (H, W) uint8, top row first.

    The read binding and pack alignment are restored afterwards.
    """
    gl = _gl()
    w, h = size
    out = np.zeros((h, w), np.uint8)
    previous = _read(gl.glGetIntegerv, _INTS["read_framebuffer"][0], 1, ctypes.c_int)
    align = _read(gl.glGetIntegerv, _GL_PACK_ALIGNMENT, 1, ctypes.c_int)
    gl.glBindFramebuffer(_GL_READ_FRAMEBUFFER, framebuffer.glo)
    gl.glPixelStorei(_GL_PACK_ALIGNMENT, 1)
    gl.glReadPixels(0, 0, w, h, _GL_STENCIL_INDEX, _GL_UNSIGNED_BYTE, out.ctypes.data)
    gl.glPixelStorei(_GL_PACK_ALIGNMENT, align)
    gl.glBindFramebuffer(_GL_READ_FRAMEBUFFER, previous)
    return out[::-1].copy()
