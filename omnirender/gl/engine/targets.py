"""The offscreen targets of a frame: made from their :class:`~.passes.Target` descriptions, kept while later
frames describe the same targets, released when no pass uses them any more."""

from __future__ import annotations

from typing import Any

from .imagespace import RenderTarget
from .passes import Target

__all__ = ["FrameTargets"]


class FrameTargets:
    """GPU targets by (description, pixel size), and the targets named in the current frame."""

    def __init__(self, ctx: Any, raw: Any, max_texture_size: int) -> None:
        self.ctx = ctx
        self.raw = raw
        self.max_texture_size = max_texture_size
        self._cache: dict[tuple[Target, tuple[int, int]], RenderTarget] = {}
        self._used: set[tuple[Target, tuple[int, int]]] = set()
        self._named: dict[str, RenderTarget] = {}
        self._frame_size: tuple[int, int] = (1, 1)

    def begin_frame(self, frame_size: tuple[int, int]) -> None:
        """A frame of the engine's ``frame_size`` starts: no target is named or used yet."""
        self._frame_size = tuple(frame_size)  # type: ignore[assignment]
        self._used = set()
        self._named = {}

    def frame_size(self, size: tuple[int, int] | None = None) -> tuple[int, int]:
        """The size targets relative to the frame are made at; with ``size``, set it (a frame drawn inside a
        target of that size, e.g. a stereo eye) and return the previous one, to be set back."""
        previous = self._frame_size
        if size is not None:
            self._frame_size = (int(size[0]), int(size[1]))
        return previous

    def named(self, name: str) -> RenderTarget:
        """The target ``name`` of the current frame (KeyError naming the fix when no pass made it)."""
        found = self._named.get(name)
        if found is None:
            known = sorted(self._named)
            raise KeyError(
                f"GLEngine: no offscreen target {name!r} in this frame (targets: {known}); a pass makes one with "
                f"Pass(target=om.gl.Target({name!r}))"
            )
        return found

    def key(
        self, description: Target, enclosing: tuple[int, int], size: tuple[int, int] | None = None
    ) -> tuple[Target, tuple[int, int]]:
        """(description, pixel size): ``size``, else the description's own, else its scale of the frame
        (or of the ``enclosing`` target's size for ``relative="enclosing"``)."""
        if size is None:
            size = description.size
        if size is None:
            base = enclosing if description.relative == "enclosing" else self._frame_size
            size = (max(1, round(base[0] * description.scale)), max(1, round(base[1] * description.scale)))
        return description, size

    def get(self, description: Target, enclosing: tuple[int, int], size: tuple[int, int] | None = None) -> RenderTarget:
        """The GPU target of ``description`` (made or kept), named in this frame."""
        key = self.key(description, enclosing, size)
        size = key[1]
        target = self._cache.get(key)
        shared = self.named(description.depth).depth if isinstance(description.depth, str) else None
        if target is not None and target.shared_depth is not shared:  # the target it shares depth with is new
            self._cache.pop(key).release()
            target = None
        if target is None:
            if max(size) > self.max_texture_size:
                raise ValueError(
                    f"GLEngine: target {description.name!r} of {size[0]}x{size[1]} pixels is larger than this GPU "
                    f"allows ({self.max_texture_size} per side); lower its size or resolution"
                )
            target = RenderTarget(self.ctx, description, size, self.raw, shared)
            self._cache[key] = target
        self._used.add(key)
        self._named[description.name] = target
        return target

    def keep(self, description: Target, enclosing: tuple[int, int]) -> bool:
        """Keep the target of ``description`` from the last frame in this one (False when it is gone)."""
        key = self.key(description, enclosing)
        target = self._cache.get(key)
        if target is None:
            return False
        self._used.add(key)
        self._named[description.name] = target
        return True

    def release_unused(self) -> None:
        """Release the targets no pass of this frame used."""
        unused = [k for k in self._cache if k not in self._used]
        if unused:
            self.ctx.finish()  # deleting a texture with queued work leaks that work in llvmpipe
        for key in unused:
            self._cache.pop(key).release()

    def release(self) -> None:
        for target in self._cache.values():
            target.release()
        self._cache.clear()
