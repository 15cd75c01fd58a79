"""om.gl: the OpenGL adapter (moderngl, headless EGL by default).

``om.gl.render(scene, size)`` renders once; ``om.gl.GLEngine(size)`` renders
frame after frame with ``engine.render(scene)``.  GL-specific attributes
(``DepthTest``, ``DepthMask``, ``Blend``, ``CullFace``, ``PolygonOffset``,
``ColorMask``, ``StencilTest``, ``StencilOp``, ``ScissorTest``,
``AlphaTest``) and GL techniques (``GLTechnique``, the default
``Forward`` and the deferred pipeline ``Deferred`` with its ``ShadingModel`` and
``MaterialDescription`` materials, described pass by pass with ``Pass``, ``Target``, ``Clear``,
``Shader``, ``FullScreen`` and ``PingPong``; ``Pass(custom=...)`` runs
Python drawing code in a pass) live here; other engines ignore them.
``capture_state`` / ``preserved_state`` snapshot and restore the GL raster
state (``GLStateSnapshot``).  moderngl is imported only when an engine is
created.
"""

from __future__ import annotations

import importlib
import os
import threading
from typing import Any

from .engine.attributes import (
    AlphaTest,
    Blend,
    ColorMask,
    CullFace,
    DepthClamp,
    DepthMask,
    DepthTest,
    GLState,
    PolygonOffset,
    ScissorTest,
    StencilOp,
    StencilTest,
)
from .engine.imagespace import PingPong
from .engine.passes import Clear, FullScreen, Pass, Shader, Target

__all__ = [
    "render",
    "available",
    "GLEngine",
    "GLTechnique",
    "Forward",
    "FrameStage",
    "ShadowMaps",
    "ShadowVolumes",
    "SurfaceStyle",
    "PhongHighlight",
    "Supersample",
    "Deferred",
    "Stereo",
    "RenderTexture",
    "Refraction",
    "ShadingModel",
    "MaterialDescription",
    "ShadingModelError",
    "BufferLayout",
    "PostProcess",
    "FXAA",
    "ToneMap",
    "Bloom",
    "SSAO",
    "DepthFog",
    "Vignette",
    "LightShafts",
    "DepthOfField",
    "ColorGrading",
    "CustomEffect",
    "Pass",
    "Target",
    "Clear",
    "Shader",
    "FullScreen",
    "PingPong",
    "GLState",
    "ScissorTest",
    "AlphaTest",
    "FramebufferStack",
    "DepthSprite",
    "DepthTest",
    "DepthMask",
    "DepthClamp",
    "Blend",
    "CullFace",
    "PolygonOffset",
    "ColorMask",
    "StencilTest",
    "StencilOp",
    "GLStateSnapshot",
    "capture_state",
    "preserved_state",
]

_LAZY = {
    "GLEngine": "glengine",
    "ShadowMaps": "techniques.shadows",
    "ShadowVolumes": "techniques.shadow_volumes",
    "SurfaceStyle": "techniques.surface_style",
    "PhongHighlight": "techniques.highlight",
    "Supersample": "techniques.supersample",
    "Deferred": "deferred",
    "Stereo": "techniques.stereo",
    "RenderTexture": "engine.render_texture",
    "Refraction": "techniques.refraction",
    "ShadingModel": "deferred",
    "MaterialDescription": "deferred",
    "ShadingModelError": "deferred",
    "BufferLayout": "deferred",
    "PostProcess": "post",
    "FXAA": "post",
    "ToneMap": "post",
    "Bloom": "post",
    "SSAO": "post",
    "DepthFog": "post",
    "Vignette": "post",
    "LightShafts": "post",
    "DepthOfField": "post",
    "ColorGrading": "post",
    "CustomEffect": "post",
    "GLTechnique": "engine.technique",
    "Forward": "techniques.forward",
    "FrameStage": "engine.stages",
    "FramebufferStack": "engine.framebuffer",
    "DepthSprite": "engine.framebuffer",
    "GLStateSnapshot": "engine.glstate",
    "capture_state": "engine.glstate",
    "preserved_state": "engine.glstate",
}
_loaded = False


def _load() -> None:
    """Import the engine and register its painters (on first use)."""
    global _loaded
    if not _loaded:
        from . import painters  # noqa: F401  (registers them)

        _loaded = True


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        _load()
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'omnirender.gl' has no attribute {name!r}")


def available() -> tuple[bool, str]:
    """Whether a headless OpenGL 3.3 context can be created here, and why not."""
    try:
        import moderngl  # noqa: F401
    except ImportError as exc:
        return False, f"moderngl is not installed ({exc}); pip install 'omnirender[gl]'"
    try:
        one_shot_context()
    except Exception as exc:
        return False, str(exc)
    return True, "OpenGL through moderngl (headless EGL)"


_one_shot = threading.local()


def one_shot_context() -> Any:
    """The hidden context one-shot renders use: one per thread (and process), made on first use, kept.

    Creating and destroying an EGL context per ``om.gl.render`` call leaks
    about 40 KB in the driver each time (2,000 calls: +80 MB) and costs a new
    context's set-up; reusing one keeps a long-running program flat.
    """
    ctx = getattr(_one_shot, "ctx", None)
    if ctx is None or _one_shot.pid != os.getpid():
        from .engine.context import create_context

        ctx = create_context()
        _one_shot.ctx, _one_shot.pid, _one_shot.programs = ctx, os.getpid(), None
    return ctx


def _one_shot_programs(ctx: Any) -> Any:
    """The shader programs compiled in the one-shot context, kept with it (compiling anew grows the driver)."""
    if _one_shot.programs is None:
        from .engine.shaders import ProgramCache

        _one_shot.programs = ProgramCache(ctx)
    return _one_shot.programs


#: What om.gl.render takes (for "did you mean" in the unknown-option error).
_GL_OPTIONS = ("size", "mask", "samples", "background", "read_depth", "on_missing", "technique", "shadows",
               "pipeline", "stereo")  # fmt: skip


def render(
    scene: Any,
    size: tuple[int, int] = (640, 480),
    mask: str | None = None,
    samples: int = 4,
    background: Any = None,
    **options: Any,
) -> Any:
    """Render ``scene`` once with a temporary :class:`GLEngine`; returns an ``om.Image``.

    ``samples`` is the multisampling count (0 turns it off), ``background`` an
    RGB(A) colour overriding the scene's ``om.Background``; further options:
    ``read_depth`` (default True: ``image.depth`` holds eye-space distances),
    ``on_missing`` (``"raise"``, ``"warn"`` or ``"skip"`` for shapes without a
    handler), ``technique`` (an ``om.Technique`` replacing the default one)
    ``shadows`` (default True: shadow maps for lights that cast shadows) and
    ``pipeline`` (``"forward"``, the default, or ``"deferred"``: ``om.gl.Deferred``) and
    ``stereo`` (an ``om.gl.Stereo``: the frame as a stereo pair).
    For many frames keep a ``GLEngine`` (or an ``om.Viewer``) instead: this
    function compiles the scene and its shaders on every call.  Calls share one
    hidden GL context per thread (see :func:`one_shot_context`); the engine's
    GPU resources are released after each call.
    """
    _load()
    from ..options import options_hint
    from .glengine import GLEngine

    read_depth = options.pop("read_depth", True)
    names = ("on_missing", "technique", "shadows", "pipeline", "stereo")
    engine_options = {key: options.pop(key) for key in names if key in options}
    if options:
        raise TypeError(
            f"om.gl.render: unknown options {sorted(options)}; it takes size, mask, samples, background, "
            "read_depth, on_missing, technique, shadows, pipeline and stereo (spp/quality are options of the "
            "mitsuba/povray engines)" + options_hint(options, _GL_OPTIONS)
        )
    from .engine.context import check_samples_total

    if isinstance(samples, int) and not isinstance(samples, bool) and samples >= 0:
        check_samples_total(size, samples)  # a size no engine would accept costs no context
    ctx = one_shot_context()
    ctx.mglo.__enter__()  # current in this thread (other engines may have made theirs current since)
    engine = GLEngine(
        size=size, samples=samples, background=background, context=ctx, programs=_one_shot_programs(ctx),
        **engine_options,
    )  # fmt: skip
    try:
        return engine.render(scene, mask=mask, read_depth=read_depth)
    finally:
        engine.release()
        _trim_heap()


def _trim_heap() -> None:
    """Give the memory the driver freed back to the system (glibc keeps large freed blocks, e.g. a shadow
    atlas, in its heap: 2,000 one-shot renders with shadows would otherwise settle 100-200 MB higher)."""
    global _malloc_trim
    if _malloc_trim is None:
        import ctypes
        import ctypes.util

        try:
            _malloc_trim = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
            _malloc_trim.argtypes, _malloc_trim.restype = [ctypes.c_size_t], ctypes.c_int
        except (OSError, AttributeError):  # not glibc: nothing to do
            _malloc_trim = False
    if _malloc_trim:
        _malloc_trim(0)


_malloc_trim: Any = None
