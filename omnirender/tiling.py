"""Tiled rendering: images larger than an engine renders at once, with bounded memory.

``om.render(scene, size=(20000, 20000), tile=1024)`` renders the image as
tiles of at most ``tile`` x ``tile`` pixels and stitches them; the GL engine
tiles on its own when ``size`` is beyond its framebuffer limit.
:func:`render_to_file` streams the tiles into a PNG file row by row instead,
so a poster needs memory for one row of tiles, never for the whole image.

Each tile is the full image's view through an **off-axis projection**: the
camera's projection for the whole image's aspect, followed by the clip-space
scale and shift that maps the tile's rectangle of the image onto the tile's
viewport (what ``gluPickMatrix`` does).  Pixel centres, line widths, point
sizes and levels of detail are therefore those of the untiled image.  Each
tile is rendered with a **guard band** of ``margin`` pixels on every side that
lies inside the image (default 64) and cropped, so that screen-space effects
reading their neighbourhood (FXAA, SSAO and its 4x4 noise pattern, depth of
field, the MSAA resolve) see the same pixels as in the untiled image; tile
rows are laid out from the bottom of the image and tile sizes and margins are
multiples of 16, so pixel-position patterns keep their phase.

Limits (documented, not silent: :func:`render_tiled` warns about them):
effects that look at the whole image — ``Bloom`` (its blur pyramid),
``LightShafts`` (rays towards the light's position on screen), ``Vignette``
(the distance to the image centre), ``ToneMap(auto_exposure=True)`` (the
image's mean luminance) and ``CustomEffect`` — are computed per
tile and can show seams; 2D overlays placed in pixels (text, HUD items) are
placed per tile.  Only the GL engine renders tiles; the offline engines render
their sizes in one piece and refuse ``tile=`` with a message saying so.
"""

from __future__ import annotations

import math
import os
import struct
import warnings
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .core.camera import Camera
from .core.transform import Matrix

__all__ = ["render_tiled", "render_to_file", "plan_tiles", "Tile", "TileCamera", "TILED_ENGINES"]

#: Engines that render tiles (the others refuse ``tile=``).
TILED_ENGINES = frozenset({"gl"})
#: Tile sizes and margins are multiples of this many pixels (pixel-position patterns keep their phase).
ALIGN = 16
#: Guard band around each tile, in pixels (FXAA, SSAO, depth of field and the MSAA resolve read neighbours).
DEFAULT_MARGIN = 64
#: Most pixels of a tiled image returned in memory (``om.render``): 1 GiB of colour, as much again of depth.
MAX_TILED_PIXELS = 1 << 28
#: Largest side of an image streamed into a file (``om.render_to_file``).
MAX_FILE_SIDE = 1 << 20
#: Effects whose result depends on the whole image: tiles of them can show seams.
WHOLE_IMAGE_EFFECTS = ("Bloom", "LightShafts", "Vignette", "CustomEffect")


@dataclass(frozen=True)
class Tile:
    """One tile: ``x, y, w, h`` is its part of the image (pixels, row 0 at the top); ``render`` the rectangle
    rendered for it (the part plus the guard band inside the image), ``(rx, ry, rw, rh)``."""

    x: int
    y: int
    w: int
    h: int
    render: tuple[int, int, int, int]

    def crop(self) -> tuple[slice, slice]:
        """Rows and columns of the rendered rectangle that are the tile's part."""
        rx, ry, _, _ = self.render
        return slice(self.y - ry, self.y - ry + self.h), slice(self.x - rx, self.x - rx + self.w)


def plan_tiles(size: tuple[int, int], tile: int, margin: int = DEFAULT_MARGIN) -> list[list[Tile]]:
    """Rows of tiles (top row first) covering an image of ``size``; rows are laid out from the image's bottom.

    ``tile`` and ``margin`` are rounded down to multiples of :data:`ALIGN`.
    """
    w, h = size
    tile = max(ALIGN, tile // ALIGN * ALIGN)
    margin = max(0, margin // ALIGN * ALIGN)
    rows: list[list[Tile]] = []
    for bottom in range(0, h, tile):  # bottom-up: GL's pixel rows count from the bottom
        top_b = min(h, bottom + tile)
        y, th = h - top_b, top_b - bottom
        ry0, ry1 = max(0, y - margin), min(h, y + th + margin)
        row = []
        for x in range(0, w, tile):
            tw = min(tile, w - x)
            rx0, rx1 = max(0, x - margin), min(w, x + tw + margin)
            row.append(Tile(x, y, tw, th, (rx0, ry0, rx1 - rx0, ry1 - ry0)))
        rows.append(row)
    rows.reverse()
    return rows


class TileCamera(Camera):
    """A camera seeing the part ``window`` of the image ``full_size`` that another camera sees whole.

    ``window = (x, y, w, h)`` in pixels of the full image (row 0 at the top).
    :meth:`projection_matrix` is the full image's projection followed by the
    clip-space scale and shift that maps the window onto the viewport; the
    ``aspect`` an engine passes is ignored (the full image's is used).
    """

    __slots__ = ("window", "full_size")

    def __init__(self, camera: Camera, full_size: tuple[int, int], window: tuple[int, int, int, int]) -> None:
        super().__init__(
            camera.eye, camera.center, camera.up, fov=camera.fov, height=camera.height,
            near=camera.near, far=camera.far, mask=camera.mask,
        )  # fmt: skip
        self.full_size = (int(full_size[0]), int(full_size[1]))
        self.window = tuple(int(v) for v in window)

    def projection_matrix(self, aspect: float) -> np.ndarray:
        width, height = self.full_size
        x, y, w, h = self.window
        base = super().projection_matrix(width / height)
        sx, sy = width / w, height / h
        cx = (2.0 * x + w) / width - 1.0  # the window's centre in the full image's NDC
        cy = 1.0 - (2.0 * y + h) / height
        m = np.eye(4)
        m[0, 0], m[0, 3] = sx, -sx * cx
        m[1, 1], m[1, 3] = sy, -sy * cy
        return m @ base


def _scene_camera(scene: Any, size: tuple[int, int], mask: str | None) -> tuple[Camera, np.ndarray, Any]:
    """(camera, its world matrix, the scene as a node): the scene's first camera, or the fitted one."""
    from .core.component import RenderingComponent
    from .core.mask import compile_mask
    from .scene.node import Node
    from .techniques.bounds import bounds

    if isinstance(scene, Node):
        node = scene
    else:
        node = Node("scene", [scene] if isinstance(scene, RenderingComponent) else list(scene))
    placed = node.declarations(None if mask is None else compile_mask(mask)).camera
    if placed is not None:
        camera, world = placed
        return camera, np.asarray(world, np.float64), node
    return Camera.fitted(bounds(node, mask=mask), size), np.eye(4), node


def _tile_scene(node: Any, camera: Camera, world: np.ndarray, size: tuple[int, int], tile: Tile) -> Any:
    from .scene.node import Node

    rig = [TileCamera(camera, size, tile.render)]
    if not np.allclose(world, np.eye(4)):
        rig.insert(0, Matrix(world))
    return Node("tiled", [Node("tile-camera", rig), node])  # the first camera met is the tile's


def _check_engine(engine: str, tile: Any) -> int:
    if engine not in TILED_ENGINES:
        raise ValueError(
            f"om.render(engine={engine!r}): tile= is supported by the {', '.join(sorted(TILED_ENGINES))} engine "
            f"only; {engine} renders the whole size in one piece (within its own size limit), so leave tile= out"
        )
    if isinstance(tile, bool) or not isinstance(tile, (int, np.integer)) or tile < ALIGN:
        raise ValueError(f"om.render: tile must be a whole number of pixels >= {ALIGN}, got {tile!r}")
    return int(tile)


def _warn_whole_image_effects(node: Any, engine: str) -> None:
    from .scene.node import Node

    found: set[str] = set()
    stack, seen = [node], set()
    while stack:
        current = stack.pop()
        if id(current) in seen:
            continue
        seen.add(id(current))
        for item in current.items:
            if isinstance(item, Node):
                stack.append(item)
                continue
            for effect in (item, *getattr(item, "effects", ())):  # a PostProcess chain holds its effects
                name = type(effect).__name__
                if name in WHOLE_IMAGE_EFFECTS or getattr(effect, "auto_exposure", False):
                    found.add(name if name in WHOLE_IMAGE_EFFECTS else f"{name}(auto_exposure=True)")
    if found:
        warnings.warn(
            f"om.render(engine={engine!r}): {', '.join(sorted(found))} look(s) at the whole image and is computed "
            "per tile in a tiled render, so tiles can differ at their seams (see omnirender.tiling)",
            stacklevel=4,
        )


def _tiles(
    scene: Any, engine: str, size: tuple[int, int], tile: int, margin: int, mask: str | None, options: dict[str, Any]
) -> Iterator[tuple[list[Tile], list[Any]]]:
    """Each row of tiles with the images rendered for them, top row first."""
    from .render import render

    camera, world, node = _scene_camera(scene, size, mask)
    _warn_whole_image_effects(node, engine)
    for row in plan_tiles(size, tile, margin):
        images = []
        for t in row:
            stand_in = _tile_scene(node, camera, world, size, t)
            try:
                images.append(render(stand_in, engine=engine, size=t.render[2:], mask=mask, **options))
            finally:
                stand_in.clear()  # the stand-in lets go of the scene again
        yield row, images


def render_tiled(
    scene: Any,
    engine: str = "gl",
    size: tuple[int, int] = (640, 480),
    tile: int = 1024,
    *,
    margin: int = DEFAULT_MARGIN,
    mask: str | None = None,
    **options: Any,
) -> Any:
    """``om.render(scene, engine, size, **options)`` rendered as tiles of ``tile`` pixels and stitched.

    What ``om.render(..., tile=N)`` calls; see the module docs for how tiles
    stay seamless and for the effects that cannot.  Memory: the result (colour
    and, with ``read_depth``, depth) plus one tile's engine.
    """
    from .image import Image
    from .options import check_image_size

    size = check_image_size("om.render", size)
    tile = _check_engine(engine, tile)
    width, height = size
    if width * height > MAX_TILED_PIXELS:
        raise ValueError(
            f"om.render: size {width}x{height} ({width * height:,} pixels) is more than an image in memory holds "
            f"here ({MAX_TILED_PIXELS:,} pixels, 1 GiB of colour); render it into a file tile by tile with "
            "om.render_to_file(scene, 'poster.png', size=...), which keeps one row of tiles in memory"
        )
    color = np.empty((height, width, 4), np.uint8)
    depth: np.ndarray | None = None
    info: dict[str, Any] = {"tiles": 0, "tile": tile, "margin": margin}
    for row, images in _tiles(scene, engine, size, tile, margin, mask, options):
        for t, image in zip(row, images, strict=True):
            rows, cols = t.crop()
            color[t.y : t.y + t.h, t.x : t.x + t.w] = image.array[rows, cols]
            if image.depth is not None:
                if depth is None:
                    depth = np.full((height, width), np.inf, np.float32)
                depth[t.y : t.y + t.h, t.x : t.x + t.w] = image.depth[rows, cols]
            info["tiles"] += 1
        del images
    return Image(color, depth=depth, engine=engine, info=info)


def render_to_file(
    scene: Any,
    path: str | os.PathLike[str],
    size: tuple[int, int],
    engine: str = "gl",
    tile: int = 1024,
    *,
    margin: int = DEFAULT_MARGIN,
    mask: str | None = None,
    **options: Any,
) -> Path:
    """Render ``scene`` at ``size`` into the PNG file ``path`` tile by tile, streaming rows of tiles.

    Memory stays at one row of tiles (``width x tile x 4`` bytes) plus one
    tile's engine, whatever the image size: a 20000x20000 poster needs about
    80 MB with 1024-pixel tiles.  The file is written atomically (complete or
    absent).  Options are :func:`om.render`'s (``read_depth`` is off: a PNG
    holds no depth).
    """
    from .fileio import atomic_write
    from .options import check_image_size

    size = check_image_size("om.render_to_file", size)
    tile = _check_engine(engine, tile)
    if max(size) > MAX_FILE_SIDE:
        raise ValueError(f"om.render_to_file: size {size[0]}x{size[1]} is beyond {MAX_FILE_SIDE} pixels a side")
    target = Path(path)
    if target.suffix.lower() != ".png":
        raise ValueError(f"om.render_to_file: {str(target)!r} must be a .png file (tiles are streamed into a PNG)")
    options["read_depth"] = False
    width, height = size
    with atomic_write(target, "wb") as fh:
        writer = _PNGWriter(fh, width, height)
        for row, images in _tiles(scene, engine, size, tile, margin, mask, options):
            strip = np.empty((row[0].h, width, 4), np.uint8)
            for t, image in zip(row, images, strict=True):
                rows, cols = t.crop()
                strip[:, t.x : t.x + t.w] = image.array[rows, cols]
            del images
            writer.rows(strip)
        writer.close()
    return target


class _PNGWriter:
    """A PNG (8-bit RGBA) written row by row: rows are deflated as they come, in bounded chunks."""

    CHUNK = 1 << 20

    def __init__(self, fh: Any, width: int, height: int) -> None:
        self.fh = fh
        self.left = height
        self.width = width
        self.compressor = zlib.compressobj(6)
        self.pending = bytearray()
        fh.write(b"\x89PNG\r\n\x1a\n")
        self._chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))

    def _chunk(self, kind: bytes, data: bytes) -> None:
        self.fh.write(struct.pack(">I", len(data)) + kind + data)
        self.fh.write(struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    def _flush(self, final: bool = False) -> None:
        while len(self.pending) >= self.CHUNK or (final and self.pending):
            part = bytes(self.pending[: self.CHUNK])
            del self.pending[: self.CHUNK]
            self._chunk(b"IDAT", part)

    def rows(self, strip: np.ndarray) -> None:
        if strip.shape[1:] != (self.width, 4) or strip.shape[0] > self.left:
            raise ValueError("PNG writer: rows of the wrong size")  # pragma: no cover - guarded by the tiler
        filtered = np.zeros((strip.shape[0], 1 + self.width * 4), np.uint8)  # filter type 0 (none) per row
        filtered[:, 1:] = strip.reshape(strip.shape[0], -1)
        for start in range(0, len(filtered), 256):
            self.pending += self.compressor.compress(filtered[start : start + 256].tobytes())
            self._flush()
        self.left -= strip.shape[0]

    def close(self) -> None:
        if self.left:
            raise ValueError(f"PNG writer: {self.left} rows missing")  # pragma: no cover - guarded by the tiler
        self.pending += self.compressor.flush()
        self._flush(final=True)
        self._chunk(b"IEND", b"")


def needs_tiles(engine: str, size: tuple[int, int], samples: Any) -> int | None:
    """The tile size ``om.render`` uses for a GL image wider or taller than the driver's framebuffers, else None.

    (An image within the framebuffer limit but beyond the engine's sample
    budget is refused with advice instead: ``samples=`` or ``tile=``.)
    """
    if engine != "gl":
        return None
    from .gl.engine.context import MAX_SAMPLES_TOTAL

    count = samples if isinstance(samples, int) and not isinstance(samples, bool) and samples > 0 else 1
    top = _gl_max_size()
    if max(size) <= top:
        return None
    side = min(top - 2 * DEFAULT_MARGIN, 2048, int(math.sqrt(MAX_SAMPLES_TOTAL // count)) // 2)
    return max(ALIGN, side // ALIGN * ALIGN)


def _gl_max_size() -> int:
    from .gl import one_shot_context
    from .gl.engine.context import limits

    try:
        ctx = one_shot_context()
    except Exception:  # no GL here: the render itself reports why
        return 1 << 30
    return min(limits(ctx))
