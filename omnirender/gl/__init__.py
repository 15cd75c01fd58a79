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
from typing import Any

from .attributes import (
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
from .imagespace import PingPong
from .passes import Clear, FullScreen, Pass, Shader, Target

__all__ = [
    "render",
    "available",
    "GLEngine",
    "GLTechnique",
    "Forward",
    "ShadowMaps",
    "ShadowVolumes",
    "SurfaceStyle",
    "PhongHighlight",
    "Supersample",
    "Deferred",
    "ShadingModel",
    "MaterialDescription",
    "ShadingModelError",
    "BufferLayout",
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
    "GLEngine": "engine",
    "ShadowMaps": "shadows",
    "ShadowVolumes": "shadow_volumes",
    "SurfaceStyle": "surface_style",
    "PhongHighlight": "highlight",
    "Supersample": "supersample",
    "Deferred": "deferred",
    "ShadingModel": "deferred",
    "MaterialDescription": "deferred",
    "ShadingModelError": "deferred",
    "BufferLayout": "deferred",
    "GLTechnique": "techniques",
    "Forward": "techniques",
    "FramebufferStack": "framebuffer",
    "DepthSprite": "framebuffer",
    "GLStateSnapshot": "glstate",
    "capture_state": "glstate",
    "preserved_state": "glstate",
}
_loaded = False


def _load() -> None:
    """Import the engine and register its painters (on first use)."""
    global _loaded
    if not _loaded:
        from . import attribute_painters, painters  # noqa: F401

        for name in ("text", "volume"):
            try:
                importlib.import_module(f".{name}", __name__)
            except ModuleNotFoundError as exc:  # optional painters not written yet
                if exc.name != f"{__name__}.{name}":
                    raise
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
        from .context import create_context

        ctx = create_context()
        ctx.release()
    except Exception as exc:
        return False, str(exc)
    return True, "OpenGL through moderngl (headless EGL)"


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
    ``pipeline`` (``"forward"``, the default, or ``"deferred"``: ``om.gl.Deferred``).
    For many frames keep a ``GLEngine`` (or an ``om.Viewer``) instead: this
    function creates and releases a GL context on every call.
    """
    _load()
    from .engine import GLEngine

    read_depth = options.pop("read_depth", True)
    names = ("on_missing", "technique", "shadows", "pipeline")
    engine_options = {key: options.pop(key) for key in names if key in options}
    if options:
        raise TypeError(
            f"om.gl.render: unknown options {sorted(options)}; it takes size, mask, samples, background, "
            "read_depth, on_missing, technique, shadows and pipeline (spp/quality are options of the mitsuba/povray "
            "engines)"
        )
    engine = GLEngine(size=size, samples=samples, background=background, **engine_options)
    try:
        return engine.render(scene, mask=mask, read_depth=read_depth)
    finally:
        engine.release()
