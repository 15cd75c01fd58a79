"""OpenGL contexts: a headless EGL context by default, limits, and raw GL entry points.

moderngl does not expose stencil functions; those few calls go through the
process's libOpenGL (GLVND dispatches them to the current context).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
from typing import Any

from .glenum import (
    GL_ALWAYS,
    GL_ATTACHMENT_OBJECT_NAME,
    GL_ATTACHMENT_OBJECT_TYPE,
    GL_CLAMP_TO_EDGE,
    GL_COLOR_ATTACHMENT0,
    GL_COLOR_BUFFER_BIT,
    GL_DECR,
    GL_DECR_WRAP,
    GL_DEPTH24_STENCIL8,
    GL_DEPTH_ATTACHMENT,
    GL_DEPTH_BUFFER_BIT,
    GL_DEPTH_STENCIL,
    GL_DEPTH_STENCIL_ATTACHMENT,
    GL_DRAW_FRAMEBUFFER,
    GL_DRAW_FRAMEBUFFER_BINDING,
    GL_EQUAL,
    GL_FRAMEBUFFER,
    GL_FRAMEBUFFER_BINDING,
    GL_FRAMEBUFFER_COMPLETE,
    GL_GEQUAL,
    GL_GREATER,
    GL_INCR,
    GL_INCR_WRAP,
    GL_INVERT,
    GL_KEEP,
    GL_LEQUAL,
    GL_LESS,
    GL_NEAREST,
    GL_NEVER,
    GL_NOTEQUAL,
    GL_PACK_INVERT_MESA,
    GL_READ_FRAMEBUFFER,
    GL_READ_FRAMEBUFFER_BINDING,
    GL_RENDERBUFFER,
    GL_REPLACE,
    GL_SAMPLE_POSITION,
    GL_SCISSOR_TEST,
    GL_STENCIL_ATTACHMENT,
    GL_STENCIL_BUFFER_BIT,
    GL_STENCIL_TEST,
    GL_TEXTURE_2D,
    GL_TEXTURE_2D_MULTISAMPLE,
    GL_TEXTURE_MAG_FILTER,
    GL_TEXTURE_MIN_FILTER,
    GL_TEXTURE_WRAP_S,
    GL_TEXTURE_WRAP_T,
    GL_UNSIGNED_INT_24_8,
)

__all__ = ["create_context", "check_size", "gl_renderer", "RawGL", "GLError", "SIGNATURES"]


class GLError(RuntimeError):
    """An OpenGL failure reported with a readable explanation (out of memory, no context)."""


def create_context(require: int = 330) -> Any:
    """A headless OpenGL context (EGL), at least version ``require`` (330 = OpenGL 3.3 core)."""
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise GLError(f"GLEngine: moderngl is not installed ({exc}); pip install 'omnirender[gl]'") from None
    if os.environ.get("GALLIUM_NOOP") == "1":
        # Mesa's no-op driver (22.x) under its threaded context corrupts memory when part of a buffer that a
        # draw used is rewritten (glBufferSubData after a draw; our offsets are in range, llvmpipe and GPUs are
        # fine): run it unthreaded, as llvmpipe runs.  Read when the first context is made.
        os.environ.setdefault("GALLIUM_THREAD", "0")
    try:
        return moderngl.create_standalone_context(backend="egl", require=require)
    except Exception as exc:
        raise GLError(
            f"GLEngine: cannot create a headless OpenGL {require // 100}.{require % 100 // 10} context through EGL "
            f"({exc}); install Mesa's EGL (libegl1, libgl1-mesa-dri) or pass context= a moderngl context"
        ) from None


def gl_renderer() -> str:
    """The name of the OpenGL implementation a headless context gets here ("unknown" without one).

    Benchmarks print it next to their figures (llvmpipe and a GPU differ by orders of magnitude).
    """
    try:
        ctx = create_context()
    except GLError:
        return "unknown"
    try:
        return str(ctx.info.get("GL_RENDERER", "unknown"))
    finally:
        ctx.release()


def limits(ctx: Any) -> tuple[int, int]:
    """(max renderbuffer size, max viewport dimension) of the context."""
    info = ctx.info
    rb = int(info.get("GL_MAX_RENDERBUFFER_SIZE", 4096))
    vp = info.get("GL_MAX_VIEWPORT_DIMS", (rb, rb))
    return rb, int(min(vp))


#: Most samples (pixels times the multisampling count) a GL engine's framebuffers hold: 8 bytes each.
MAX_SAMPLES_TOTAL = 1 << 28


def check_samples_total(size: Any, samples: int = 0) -> tuple[int, int]:
    """``size`` as (w, h) ints, or ValueError when zero, negative or (with ``samples`` multisampling)
    above :data:`MAX_SAMPLES_TOTAL` samples in all; needs no context (checked before creating one)."""
    from ...options import check_image_size

    w, h = check_image_size("GLEngine", size)
    if w * h * max(1, samples) > MAX_SAMPLES_TOTAL:
        raise ValueError(
            f"GLEngine: size {w}x{h} with {max(1, samples)} sample(s) per pixel needs {w * h * max(1, samples):,} "
            f"samples, more than the {MAX_SAMPLES_TOTAL:,} (2 GiB of colour and depth) this engine allocates; "
            "render a smaller image, with fewer samples=, in tiles (om.render(..., tile=2048)), or into a "
            "file tile by tile (om.render_to_file)"
        )
    return w, h


def check_size(size: Any, ctx: Any, samples: int = 0) -> tuple[int, int]:
    """:func:`check_samples_total`, and ValueError above the driver's maximum framebuffer size."""
    w, h = check_samples_total(size, samples)
    rb, vp = limits(ctx)
    top = min(rb, vp)
    if w > top or h > top:
        raise ValueError(
            f"GLEngine: size {w}x{h} exceeds this driver's maximum framebuffer size {top}x{top} "
            f"(GL_MAX_RENDERBUFFER_SIZE / GL_MAX_VIEWPORT_DIMS); om.render(scene, size=...) renders such an "
            "image in tiles (omnirender.tiling), or render a smaller one"
        )
    return w, h


_STENCIL_FUNCS = {
    "never": GL_NEVER,
    "less": GL_LESS,
    "equal": GL_EQUAL,
    "lequal": GL_LEQUAL,
    "greater": GL_GREATER,
    "notequal": GL_NOTEQUAL,
    "gequal": GL_GEQUAL,
    "always": GL_ALWAYS,
}
_STENCIL_OPS = {
    "keep": GL_KEEP,
    "zero": 0,
    "replace": GL_REPLACE,
    "incr": GL_INCR,
    "decr": GL_DECR,
    "invert": GL_INVERT,
    "incr_wrap": GL_INCR_WRAP,
    "decr_wrap": GL_DECR_WRAP,
}

_u, _i, _f, _d, _b = ctypes.c_uint, ctypes.c_int, ctypes.c_float, ctypes.c_double, ctypes.c_ubyte
_pi, _pu, _pf, _pb = ctypes.POINTER(_i), ctypes.POINTER(_u), ctypes.POINTER(_f), ctypes.POINTER(_b)
#: The GL entry points moderngl lacks: name -> (argument types, result type), as the GL headers declare
#: them (GLenum/GLbitfield/GLuint -> c_uint, GLint/GLsizei -> c_int, GLboolean -> c_ubyte).  Every raw
#: call goes through this table: ctypes' default result type is a C int, and reading a GLboolean (one
#: byte) as an int takes whatever the driver left in the register's upper bytes (-962556927 for
#: GL_TRUE on NVIDIA's driver).
SIGNATURES: dict[str, tuple[list[Any], Any]] = {
    "glStencilFunc": ([_u, _i, _u], None),
    "glStencilOp": ([_u, _u, _u], None),
    "glStencilMask": ([_u], None),
    "glIsRenderbuffer": ([_u], _b),
    "glIsFramebuffer": ([_u], _b),
    "glIsTexture": ([_u], _b),
    "glGenFramebuffers": ([_i, _pu], None),
    "glGenRenderbuffers": ([_i, _pu], None),
    "glDeleteRenderbuffers": ([_i, _pu], None),
    "glBindFramebuffer": ([_u, _u], None),
    "glBindRenderbuffer": ([_u, _u], None),
    "glRenderbufferStorageMultisample": ([_u, _i, _u, _i, _i], None),
    "glFramebufferRenderbuffer": ([_u, _u, _u, _u], None),
    "glCheckFramebufferStatus": ([_u], _u),
    "glBlitFramebuffer": ([_i, _i, _i, _i, _i, _i, _i, _i, _u, _u], None),
    "glClearStencil": ([_i], None),
    "glClearColor": ([_f, _f, _f, _f], None),
    "glClear": ([_u], None),
    "glClearDepth": ([_d], None),
    "glFinish": ([], None),
    "glGetIntegerv": ([_u, _pi], None),
    "glGetFloatv": ([_u, _pf], None),
    "glGetBooleanv": ([_u, _pb], None),
    "glIsEnabled": ([_u], _b),
    "glEnable": ([_u], None),
    "glDisable": ([_u], None),
    "glColorMask": ([_b, _b, _b, _b], None),
    "glDepthMask": ([_b], None),
    "glTexParameteri": ([_u, _u, _i], None),
    "glViewport": ([_i, _i, _i, _i], None),
    "glScissor": ([_i, _i, _i, _i], None),
    "glDepthFunc": ([_u], None),
    "glBlendFuncSeparate": ([_u, _u, _u, _u], None),
    "glBlendEquationSeparate": ([_u, _u], None),
    "glBlendColor": ([_f, _f, _f, _f], None),
    "glCullFace": ([_u], None),
    "glFrontFace": ([_u], None),
    "glPolygonMode": ([_u, _u], None),
    "glPolygonOffset": ([_f, _f], None),
    "glLineWidth": ([_f], None),
    "glPointSize": ([_f], None),
    "glDepthRange": ([_d, _d], None),
    "glStencilFuncSeparate": ([_u, _u, _i, _u], None),
    "glStencilOpSeparate": ([_u, _u, _u, _u], None),
    "glStencilMaskSeparate": ([_u, _u], None),
    "glSampleCoverage": ([_f, _b], None),
    "glProvokingVertex": ([_u], None),
    "glReadPixels": ([_i, _i, _i, _i, _u, _u, ctypes.c_void_p], None),
    "glPixelStorei": ([_u, _i], None),
    "glGenTextures": ([_i, _pu], None),
    "glDeleteTextures": ([_i, _pu], None),
    "glBindTexture": ([_u, _u], None),
    "glDeleteFramebuffers": ([_i, _pu], None),
    "glTexImage2D": ([_u, _i, _i, _i, _i, _i, _u, _u, ctypes.c_void_p], None),
    "glFramebufferTexture2D": ([_u, _u, _u, _u, _i], None),
    "glGetFramebufferAttachmentParameteriv": ([_u, _u, _u, _pi], None),
    "glDrawBuffers": ([_i, _pu], None),
    "glGetMultisamplefv": ([_u, _u, _pf], None),
    "glSampleMaski": ([_u, _u], None),
}


class RawGL:
    """The handful of GL calls moderngl lacks (stencil state, glGet*), loaded from libOpenGL/libGL.

    Each entry point of :data:`SIGNATURES` is an attribute with its declared argument and result
    types; names outside the table are not reachable (an undeclared call would guess its types).
    """

    _lib: Any = None

    def __init__(self) -> None:
        if RawGL._lib is None:
            for name in ("OpenGL", "GL"):
                path = ctypes.util.find_library(name)
                if path:
                    try:
                        RawGL._lib = ctypes.CDLL(path)
                        break
                    except OSError:
                        continue
        lib = RawGL._lib
        self.available = lib is not None
        if lib is not None:
            for name, (args, result) in SIGNATURES.items():
                fn = getattr(lib, name)
                fn.argtypes = args
                fn.restype = result
                setattr(self, name, fn)
            self._func, self._op, self._mask = self.glStencilFunc, self.glStencilOp, self.glStencilMask

    def _require(self) -> None:
        if not self.available:
            raise GLError("GLEngine: StencilTest needs libOpenGL/libGL to set stencil state, which was not found")

    def stencil_test(self, ctx: Any, test: tuple | None) -> None:
        """Enable the stencil test with ``(func, ref, mask)``, or disable it (None)."""
        if test is None:
            ctx.disable_direct(GL_STENCIL_TEST)
            return
        self._require()
        func, ref, mask = test
        ctx.enable_direct(GL_STENCIL_TEST)
        self._func(_STENCIL_FUNCS[func], int(ref), int(mask) & 0xFFFFFFFF)

    def stencil_op(self, fail: str, zfail: str, zpass: str, write_mask: int) -> None:
        """glStencilOp and glStencilMask (the write mask)."""
        if not self.available:
            return  # without libGL there is no stencil test either; the default op changes nothing
        self._op(_STENCIL_OPS[fail], _STENCIL_OPS[zfail], _STENCIL_OPS[zpass])
        self._mask(int(write_mask) & 0xFFFFFFFF)


def depth_stencil_framebuffer(ctx: Any, raw: RawGL, color: Any, size: tuple[int, int], samples: int) -> Any:
    """A framebuffer with ``color`` (a moderngl renderbuffer) and a 24/8 depth-stencil renderbuffer, or None.

    moderngl offers no stencil attachment; the framebuffer is built with raw GL
    calls and wrapped with ``ctx.detect_framebuffer``.  Returns None when the
    raw entry points are unavailable or the driver rejects the format.
    """
    if not raw.available:
        return None
    try:
        previous = ctypes.c_int(0)
        raw.glGetIntegerv(GL_FRAMEBUFFER_BINDING, ctypes.byref(previous))
        fbo = ctypes.c_uint(0)
        rbo = ctypes.c_uint(0)
        raw.glGenFramebuffers(1, ctypes.byref(fbo))
        raw.glGenRenderbuffers(1, ctypes.byref(rbo))
        raw.glBindRenderbuffer(GL_RENDERBUFFER, rbo.value)
        raw.glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH24_STENCIL8, size[0], size[1])
        raw.glBindFramebuffer(GL_FRAMEBUFFER, fbo.value)
        raw.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color.glo)
        raw.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, rbo.value)
        ok = raw.glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE
        raw.glBindFramebuffer(GL_FRAMEBUFFER, previous.value)
        if not ok:
            raw.glDeleteRenderbuffers(1, ctypes.byref(rbo))
            return None
        wrapped = ctx.detect_framebuffer(fbo.value)
        return wrapped, rbo.value
    except Exception:  # pragma: no cover - depends on the driver
        return None


def delete_renderbuffer(raw: RawGL, rbo: int) -> None:
    """Delete a renderbuffer made by :func:`depth_stencil_framebuffer`."""
    if raw.available:
        name = ctypes.c_uint(rbo)
        raw.glDeleteRenderbuffers(1, ctypes.byref(name))


def depth_stencil_target(ctx: Any, raw: RawGL, colors: list[Any], size: tuple[int, int]) -> tuple | None:
    """A framebuffer of moderngl colour textures and a 24/8 depth-stencil *texture*, or None.

    Returns (framebuffer, depth texture wrapped for sampling, release function).
    moderngl makes depth textures without stencil; offscreen passes that need
    both (shadow volumes into a float target) get this one, built with raw GL.
    """
    if not raw.available:
        return None
    previous = ctypes.c_int(0)
    raw.glGetIntegerv(GL_FRAMEBUFFER_BINDING, ctypes.byref(previous))
    tex = ctypes.c_uint(0)
    fbo = ctypes.c_uint(0)
    raw.glGenTextures(1, ctypes.byref(tex))
    raw.glBindTexture(GL_TEXTURE_2D, tex.value)
    raw.glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH24_STENCIL8, size[0], size[1], 0, GL_DEPTH_STENCIL,
                     GL_UNSIGNED_INT_24_8, None)  # fmt: skip
    for pname, value in ((GL_TEXTURE_MIN_FILTER, GL_NEAREST), (GL_TEXTURE_MAG_FILTER, GL_NEAREST),
                         (GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE), (GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE)):  # fmt: skip
        raw.glTexParameteri(GL_TEXTURE_2D, pname, value)
    raw.glBindTexture(GL_TEXTURE_2D, 0)
    raw.glGenFramebuffers(1, ctypes.byref(fbo))
    raw.glBindFramebuffer(GL_FRAMEBUFFER, fbo.value)
    for i, color in enumerate(colors):
        raw.glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, color.glo, 0)
    raw.glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, tex.value, 0)
    ok = raw.glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE
    raw.glBindFramebuffer(GL_FRAMEBUFFER, previous.value)

    def release() -> None:
        raw.glDeleteFramebuffers(1, ctypes.byref(fbo))
        raw.glDeleteTextures(1, ctypes.byref(tex))

    if not ok:
        release()
        return None
    wrapped = ctx.detect_framebuffer(fbo.value)
    depth = ctx.external_texture(tex.value, size, 1, 0, "f4")
    return wrapped, depth, release


def set_masks(ctx: Any, raw: RawGL, fbo: Any, color: tuple | None = None, depth: bool | None = None) -> None:
    """Set colour and depth write masks (raw GL when available: moderngl ignores them on detected framebuffers)."""
    if raw.available:
        if color is not None:
            raw.glColorMask(bool(color[0]), bool(color[1]), bool(color[2]), bool(color[3]))
        if depth is not None:
            raw.glDepthMask(bool(depth))
        return
    if color is not None:
        fbo.color_mask = tuple(bool(c) for c in color)
    if depth is not None:
        fbo.depth_mask = bool(depth)


def clear_stencil_bits(raw: RawGL, bits: int) -> None:
    """Set the stencil ``bits`` of the bound framebuffer to 0, keeping the others (scissor test off)."""
    if raw.available:
        raw.glDisable(GL_SCISSOR_TEST)
        raw._mask(int(bits) & 0xFF)
        raw.glClearStencil(0)
        raw.glClear(GL_STENCIL_BUFFER_BIT)
        raw._mask(0xFF)


def clear_stencil_value(raw: RawGL, value: int = 0) -> None:
    """Clear the stencil buffer of the bound framebuffer to ``value`` under the state set now (write mask, scissor:
    the caller sets them through the state applier)."""
    if raw.available:
        raw.glClearStencil(int(value))
        raw.glClear(GL_STENCIL_BUFFER_BIT)


def reads_top_down(ctx: Any, raw: RawGL) -> bool:
    """Whether :func:`read_color_top_down` reads rows top-down in the read itself (Mesa's ``GL_MESA_pack_invert``)."""
    return raw.available and "GL_MESA_pack_invert" in ctx.extensions


def read_color_top_down(raw: RawGL, fbo: Any, out: Any) -> None:
    """Read ``fbo``'s colour as RGBA8 into ``out`` ((h, w, 4) uint8, C order) with its rows top-down, the way an
    image is stored, in the read itself (no copy to flip the rows).  Only where :func:`reads_top_down` says so;
    the pack state is back at GL's default (bottom-up) afterwards."""
    raw.glPixelStorei(GL_PACK_INVERT_MESA, 1)
    try:
        fbo.read_into(out, components=4, alignment=1)
    finally:
        raw.glPixelStorei(GL_PACK_INVERT_MESA, 0)


def clear_frame(raw: RawGL, color: tuple[float, ...], stencil: bool) -> None:
    """Clear the bound framebuffer's colour to ``color`` (RGBA; alpha 0 when not given, as moderngl), depth to 1
    and, with ``stencil``, stencil to 0 (colour and depth in one glClear, stencil in a second).  Only while every
    kind is at its default (every channel, depth and stencil bit written, no scissor: a frame's begin) and
    ``raw.available``."""
    r, g, b, a = (*color, 0.0, 0.0, 0.0, 0.0)[:4]
    raw.glClearColor(r, g, b, a)
    raw.glClearDepth(1.0)
    raw.glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    if stencil:
        # stencil in a clear of its own: Mesa's softpipe, given depth and stencil in one glClear, leaves depth
        # that a translucent surface's second frame tests differently (1/255 off a fresh engine's picture,
        # tests/gl/test_single_changes.py in the softpipe CI step)
        raw.glClearStencil(0)
        raw.glClear(GL_STENCIL_BUFFER_BIT)


def clear_depth(raw: RawGL, value: float = 1.0, scissored: bool = False) -> None:
    """Clear the depth buffer of the bound framebuffer only (colour and stencil untouched; scissor test off, or
    with ``scissored`` the scissor the caller set through the state applier)."""
    if not scissored:
        raw.glDisable(GL_SCISSOR_TEST)
    raw.glDepthMask(1)
    raw.glClearDepth(float(value))
    raw.glClear(GL_DEPTH_BUFFER_BIT)


def clear_stencil(raw: RawGL, value: int = 0) -> None:
    """Clear the stencil buffer of the bound framebuffer (every bit: glClear obeys the stencil write mask)."""
    if raw.available:
        raw._mask(0xFF)
        raw.glClearStencil(int(value))
        raw.glClear(GL_STENCIL_BUFFER_BIT)


def blit(raw: RawGL, source: Any, target: Any, size: tuple[int, int], color: bool, depth: bool) -> None:
    """Copy colour (the read buffer to the draw buffers) and/or depth of framebuffer ``source`` into ``target``.

    Both are moderngl framebuffers of ``size``; a multisampled source is resolved.  The framebuffer
    bindings are restored afterwards (moderngl's idea of the bound framebuffer stays true).
    """
    previous_draw, previous_read = ctypes.c_int(0), ctypes.c_int(0)
    raw.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, ctypes.byref(previous_draw))
    raw.glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, ctypes.byref(previous_read))
    raw.glBindFramebuffer(GL_READ_FRAMEBUFFER, source.glo)
    raw.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, target.glo)
    bits = (GL_COLOR_BUFFER_BIT if color else 0) | (GL_DEPTH_BUFFER_BIT if depth else 0)
    w, h = size
    raw.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, bits, GL_NEAREST)
    raw.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, previous_draw.value)
    raw.glBindFramebuffer(GL_READ_FRAMEBUFFER, previous_read.value)


def _attachment(raw: RawGL, point: int) -> tuple[int, int]:
    """(object type, name) attached at ``point`` of the bound draw framebuffer (type 0: nothing)."""
    kind, name = ctypes.c_int(0), ctypes.c_int(0)
    raw.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, point, GL_ATTACHMENT_OBJECT_TYPE, ctypes.byref(kind))
    if kind.value:
        raw.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, point, GL_ATTACHMENT_OBJECT_NAME,
                                                  ctypes.byref(name))  # fmt: skip
    return kind.value, name.value


def sharing_depth(ctx: Any, raw: RawGL, colors: list[Any], samples: int) -> tuple[Any, Any, bool] | None:
    """A framebuffer of moderngl colour textures sharing the depth (and stencil) of the framebuffer bound now.

    Returns (framebuffer, release function, whether it has a stencil), or None when the bound
    framebuffer is the default one or has no depth attachment (its buffers cannot be shared).
    Passes that test against another pass's depth without sampling it use it (no feedback loop).
    """
    if not raw.available:
        return None
    bound = ctypes.c_int(0)
    raw.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, ctypes.byref(bound))
    if bound.value == 0:
        return None
    depth = _attachment(raw, GL_DEPTH_ATTACHMENT)
    if not depth[0]:
        return None
    stencil = _attachment(raw, GL_STENCIL_ATTACHMENT)
    target = GL_TEXTURE_2D_MULTISAMPLE if samples > 1 else GL_TEXTURE_2D
    fbo = ctypes.c_uint(0)
    raw.glGenFramebuffers(1, ctypes.byref(fbo))
    raw.glBindFramebuffer(GL_FRAMEBUFFER, fbo.value)
    for i, color in enumerate(colors):
        raw.glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, target, color.glo, 0)
    shared = stencil == depth
    point = GL_DEPTH_STENCIL_ATTACHMENT if shared else GL_DEPTH_ATTACHMENT
    if depth[0] == GL_RENDERBUFFER:
        raw.glFramebufferRenderbuffer(GL_FRAMEBUFFER, point, GL_RENDERBUFFER, depth[1])
    else:
        raw.glFramebufferTexture2D(GL_FRAMEBUFFER, point, target, depth[1], 0)
    buffers = (ctypes.c_uint * max(len(colors), 1))(*(GL_COLOR_ATTACHMENT0 + i for i in range(len(colors))))
    raw.glDrawBuffers(len(colors), buffers)
    ok = raw.glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE
    raw.glBindFramebuffer(GL_FRAMEBUFFER, bound.value)

    def release() -> None:
        raw.glDeleteFramebuffers(1, ctypes.byref(fbo))

    if not ok:
        release()
        return None
    wrapped = ctx.detect_framebuffer(fbo.value)
    _ = ctx.error  # moderngl's detection queries attachments that are not there: a harmless error to drop
    return wrapped, release, shared


def sample_positions(raw: RawGL, samples: int) -> list[tuple[float, float]]:
    """The sample positions (in [0, 1] within a pixel) of the multisampled framebuffer bound now."""
    out = []
    value = (ctypes.c_float * 2)()
    for k in range(samples):
        raw.glGetMultisamplefv(GL_SAMPLE_POSITION, k, value)
        out.append((float(value[0]), float(value[1])))
    return out


def frame_has_stencil(raw: RawGL) -> bool:
    """Whether the framebuffer bound now (not the default one) has a stencil attachment."""
    if not raw.available:
        return False
    bound = ctypes.c_int(0)
    raw.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, ctypes.byref(bound))
    return bound.value != 0 and _attachment(raw, GL_STENCIL_ATTACHMENT)[0] != 0
