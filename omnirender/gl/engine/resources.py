"""GPU allocation with readable failures, and counting of live GPU objects."""

from __future__ import annotations

from typing import Any

from .context import GLError

__all__ = ["gpu_call", "live_buffers"]


def gpu_call(fn: Any, *args: Any, what: str = "data", **kwargs: Any) -> Any:
    """Call a moderngl allocation; out-of-memory and driver errors become :class:`GLError` naming ``what``."""
    try:
        return fn(*args, **kwargs)
    except MemoryError:
        raise GLError(f"GLEngine: out of memory while uploading {what}; reduce the scene or image size") from None
    except Exception as exc:
        text = str(exc)
        if "memory" in text.lower() or "GL_OUT_OF_MEMORY" in text:
            raise GLError(
                f"GLEngine: the GPU ran out of memory while uploading {what} ({text}); reduce the scene or image size"
            ) from None
        raise


def live_buffers(ctx: Any) -> int:
    """How many moderngl Buffer objects of ``ctx`` are alive (for leak tests)."""
    import gc

    import moderngl

    return sum(
        1
        for o in gc.get_objects()
        if isinstance(o, moderngl.Buffer)
        and o.ctx is ctx
        and o.mglo is not None
        and not isinstance(o.mglo, moderngl.InvalidObject)
    )
