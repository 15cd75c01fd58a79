"""Text: a glyph atlas rendered with Pillow, drawn as a 2D overlay after the 3D scene.

The painter only records the label (a draw item of kind ``"text"`` whose
geometry is the anchor point); the drawer projects the anchor with the frame's
camera and draws one textured quad per glyph in pixel coordinates, without
depth test.  Atlases are built once per pixel size from DejaVu Sans, the font
shipped with the package (:mod:`omnirender.fonts`: the same glyphs and sizes on
every machine, whatever fonts it has installed), and kept for the engine's life.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...core.handler import ShapePainter, default_for
from ...shapes import Text
from ..engine.attributes import Blend, DepthTest
from ..engine.geometry import Geometry
from ..engine.layout import ROW
from ..glengine import GLEngine

__all__ = ["TextPainter", "GlyphAtlas"]

_VS = """
in vec2 in_pos;
in vec2 in_uv;
out vec2 v_uv;
void main() {
    v_uv = in_uv;
    gl_Position = vec4(in_pos, 0.0, 1.0);
}
"""

_FS = """
in vec2 v_uv;
uniform sampler2D u_atlas;
uniform vec4 u_color;
out vec4 f_color;
void main() {
    float a = texture(u_atlas, v_uv).r;
    if (a <= 0.0) discard;
    f_color = vec4(to_srgb(u_color.rgb), u_color.a * a);
}
"""


class GlyphAtlas:
    """Printable ASCII (and any extra characters met) rasterised at one pixel size into one texture."""

    def __init__(self, size: int, extra: str = "") -> None:
        from PIL import Image, ImageDraw, ImageFont

        from ...fonts import font_file

        try:
            font = ImageFont.truetype(str(font_file()), size)
        except ImportError as exc:  # Pillow built without FreeType
            raise RuntimeError(
                f"GLEngine: text needs Pillow with FreeType support to draw the shipped font ({exc}); "
                "install Pillow's wheel from PyPI (pip install --force-reinstall pillow)"
            ) from None
        self.size = size
        chars = sorted(set("".join(chr(c) for c in range(32, 127)) + extra))
        ascent, descent = font.getmetrics()
        self.ascent, self.descent = ascent, descent
        cell_h = ascent + descent + 2
        boxes = {ch: font.getbbox(ch) for ch in chars}
        widths = {ch: max(1, b[2] - b[0]) + 2 for ch, b in boxes.items()}
        cols_w = 512
        x = y = 0
        self.glyphs: dict[str, tuple[float, float, float, float, int, int, float]] = {}
        placements = {}
        for ch in chars:
            w = widths[ch]
            if x + w > cols_w:
                x = 0
                y += cell_h
            placements[ch] = (x, y)
            x += w
        height = y + cell_h
        img = Image.new("L", (cols_w, height), 0)
        draw = ImageDraw.Draw(img)
        for ch in chars:
            px, py = placements[ch]
            b = boxes[ch]
            draw.text((px + 1 - b[0], py + 1), ch, fill=255, font=font)
            advance = font.getlength(ch)
            # uv rectangle (u0, v0, u1, v1), size in pixels (w, h) and x offset / advance
            self.glyphs[ch] = (
                px / cols_w,
                py / height,
                (px + widths[ch]) / cols_w,
                (py + cell_h) / height,
                widths[ch],
                cell_h,
                b[0] - 1,
                advance,
            )
        self.image = np.asarray(img, dtype=np.uint8)
        self.texture: Any = None

    def quads(self, string: str, x: float, y: float) -> np.ndarray:
        """(n*6, 4) vertices (pixel x, pixel y from the bottom, u, v) for ``string`` with its baseline at y."""
        out = []
        pen = x
        base = y - self.descent - 1
        for ch in string:
            g = self.glyphs.get(ch) or self.glyphs["?"]
            u0, v0, u1, v1, w, h, off, advance = g
            x0, x1 = pen + off, pen + off + w
            y0, y1 = base, base + h
            out += [
                (x0, y1, u0, v0),
                (x0, y0, u0, v1),
                (x1, y0, u1, v1),
                (x0, y1, u0, v0),
                (x1, y0, u1, v1),
                (x1, y1, u1, v0),
            ]
            pen += advance
        return np.array(out, dtype=np.float32).reshape(-1, 4)


@default_for(GLEngine)
class TextPainter(ShapePainter):
    """Records a label; drawn last as a screen-aligned overlay at the projected position."""

    __slots__ = ()
    service = "gl.paint"
    target = Text

    def exec(self, shape: Text, engine: GLEngine) -> None:
        geom = engine.geometry_cache.get(shape)
        if geom is None:
            geom = Geometry("points", np.asarray(shape.position, np.float32)[None, :], label=f"Text {shape.string!r}")
            engine.geometry_cache.put(shape, geom)
        engine.submit(geom, kind="text", extra=(shape.string, float(shape.size)), transparent=False)


_STATE = (DepthTest(False), Blend())  # made once: state attributes are components

#: glyph atlases by engine and text size (they go with their engine)
_ATLASES: weakref.WeakKeyDictionary[Any, dict[int, Any]] = weakref.WeakKeyDictionary()


def draw_text(engine: GLEngine, items: list, state: Any) -> int:
    """The drawer for ``"text"`` items: project anchors, build glyph quads, draw without depth test."""
    ctx = engine.ctx
    if not engine.programs.registered("text"):
        engine.programs.register("text", _VS, _FS)
    prog = engine.programs.get("text")
    atlases = _ATLASES.setdefault(engine, {})
    w, h = engine.target_size
    calls = 0
    engine.apply_gl_state(*_STATE)  # over everything, blended "over"
    clip = engine.frame_projection @ engine.frame_view
    for item in items:
        string, size = item.state.extra
        if not string:
            continue
        m = item.row[ROW.slice("model")].reshape(4, 4).T.astype(np.float64)
        p = clip @ m @ np.append(item.geometry.positions[0].astype(np.float64), 1.0)
        if p[3] <= 0:
            continue
        ndc = p[:3] / p[3]
        if abs(ndc[2]) > 1.0:
            continue
        px = (ndc[0] + 1.0) * 0.5 * w
        py = (ndc[1] + 1.0) * 0.5 * h
        key = int(round(size))
        extra = "".join(ch for ch in string if not (32 <= ord(ch) < 127))
        atlas = atlases.get(key)
        if atlas is None or any(ch not in atlas.glyphs for ch in extra):
            atlas = GlyphAtlas(max(key, 4), extra + ("" if atlas is None else "".join(atlas.glyphs)))
            atlases[key] = atlas
        if atlas.texture is None:
            ah, aw = atlas.image.shape
            atlas.texture = ctx.texture((aw, ah), 1, atlas.image.tobytes())
            atlas.texture.filter = (ctx.NEAREST, ctx.NEAREST)
        verts = atlas.quads(string, round(px), round(py))
        verts[:, 0] = verts[:, 0] / w * 2.0 - 1.0
        verts[:, 1] = verts[:, 1] / h * 2.0 - 1.0
        vbo = ctx.buffer(verts.tobytes())
        vao = ctx.vertex_array(prog, [(vbo, "2f 2f", "in_pos", "in_uv")])
        atlas.texture.use(0)
        prog["u_atlas"].value = 0
        prog["u_color"].value = tuple(float(x) for x in item.row[ROW.slice("color")])
        vao.render(ctx.TRIANGLES)
        vao.release()
        vbo.release()
        calls += 1
    return calls


GLEngine.register_drawer("text", draw_text)
