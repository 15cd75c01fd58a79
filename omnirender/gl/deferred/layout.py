"""The automatic G-buffer and L-buffer layout of a set of shading models.

Fixed for every model: the depth texture and one ``rg32ui`` layer (64 bits) packing

* the eye-space normal, octahedral, 12 + 12 bits (``x`` bits 8-31);
* the material id, 12 bits (``y`` bits 20-31: a row of the material table, 0 = nothing drawn), and
  4 flag bits (``y`` bits 16-19: bit 0 receives shadows, bits 1-3 the fog slot);
* three 8-bit channels for the models' outputs (``x`` bits 0-7, ``y`` bits 8-15 and 0-7).

The models' outputs are packed into channels that all models share, since a pixel shows one
material: 8-bit channels (``unorm`` and ``color`` outputs; the first three go into the fixed layer,
the rest into ``f1`` RGBA layers), 16-bit float channels (``half``, ``rgb16``: ``f2`` layers) and
light channels (the L-buffer: layers of three channels, added up over the lights).  The width of
each kind is the *maximum* over the models, not the sum.

The light layers are ``f2`` (half floats) by default, or ``r11g11b10f`` (three unsigned small floats
in 32 bits: half the memory).  A Phong-only frame needs the fixed layer, depth and one light layer:
20 bytes per pixel (39.6 MiB at 1920x1080), or 16 with the compact light layer (31.6 MiB).  The
compact format has 6 and 5 mantissa bits: GPUs round each blend to the nearest value, but software
rasterisers (Mesa's llvmpipe) truncate it, which darkens a pixel by about 0.2 of 255 sRGB levels
per light that reaches it; so it is the choice for memory, not the default.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from ..engine.passes import FORMATS, Target
from .models import G_TYPES, L_TYPES, ShadingModel

__all__ = ["BufferLayout", "FIXED_SPARE", "GBUFFER", "Channel", "LIGHT_FORMATS"]

#: Formats of the light layers: half floats (the default), or 11/11/10-bit unsigned floats (half the memory).
LIGHT_FORMATS = ("f2", "r11g11b10f")

#: 8-bit channels of the fixed layer free for model outputs.
FIXED_SPARE = 3
#: Name of the frame's G-buffer target (the L-buffer layers are attachments of it too).
GBUFFER = "deferred.gbuffer"
#: The most colour attachments a layout may use (OpenGL guarantees 8).
MAX_ATTACHMENTS = 8


class Channel:
    """Where one component of an output lives: its kind (``"8"``, ``"16"``, ``"light"``) and index."""

    __slots__ = ("kind", "index")

    def __init__(self, kind: str, index: int) -> None:
        self.kind, self.index = kind, index

    def location(self) -> tuple[str, int]:
        """(attachment name, component) of this channel; the fixed layer's spare bytes are ``("fixed", k)``."""
        if self.kind == "8":
            if self.index < FIXED_SPARE:
                return "fixed", self.index
            k = self.index - FIXED_SPARE
            return f"g8_{k // 4}", k % 4
        if self.kind == "16":
            return f"g16_{self.index // 4}", self.index % 4
        return f"light_{self.index // 3}", self.index % 3


class BufferLayout:
    """G-buffer and L-buffer layers for a set of shading models, and where each model's outputs lie."""

    def __init__(self, models: Iterable[ShadingModel], light_format: str = "f2") -> None:
        if light_format not in LIGHT_FORMATS:
            raise ValueError(f"deferred pipeline: light_format must be one of {LIGHT_FORMATS}, got {light_format!r}")
        self.light_format = light_format
        self.models = tuple(sorted(set(models), key=lambda m: m.number))
        self.width8 = max((m.channels("8") for m in self.models), default=0)
        self.width16 = max((m.channels("16") for m in self.models), default=0)
        self.width_light = max((m.light_channels for m in self.models), default=0)
        layers: list[tuple[str, str]] = [("fixed", "rg32ui")]
        layers += [(f"g8_{k}", "f1") for k in range(math.ceil(max(self.width8 - FIXED_SPARE, 0) / 4))]
        layers += [(f"g16_{k}", "f2") for k in range(math.ceil(self.width16 / 4))]
        self.light_layers = tuple(f"light_{k}" for k in range(math.ceil(self.width_light / 3)))
        layers += [(name, light_format) for name in self.light_layers]
        if len(layers) > MAX_ATTACHMENTS:
            names = ", ".join(m.name for m in self.models)
            raise ValueError(
                f"deferred pipeline: the shading models {names} need {len(layers)} buffer layers, more than the "
                f"{MAX_ATTACHMENTS} colour attachments OpenGL guarantees; declare fewer or narrower outputs"
            )
        self.layers = tuple(layers)
        #: per model: output name -> channels (one per component)
        self.channels: dict[int, dict[str, list[Channel]]] = {}
        self.light: dict[int, dict[str, list[Channel]]] = {}
        for m in self.models:
            counters = {"8": 0, "16": 0}
            out: dict[str, list[Channel]] = {}
            for name, kind in m.gbuffer.items():
                _, size, storage, _ = G_TYPES[kind]
                out[name] = [Channel(storage, counters[storage] + i) for i in range(size)]
                counters[storage] += size
            self.channels[m.number] = out
            light: dict[str, list[Channel]] = {}
            n = 0
            for name, kind in m.lbuffer.items():
                size = L_TYPES[kind][1]
                light[name] = [Channel("light", n + i) for i in range(size)]
                n += size
            self.light[m.number] = light

    @property
    def key(self) -> tuple[Any, ...]:
        """The model numbers and light format: layouts (and the shaders made for them) are rebuilt when it changes."""
        return (*(m.number for m in self.models), self.light_format)

    @property
    def has_lbuffer(self) -> bool:
        """Whether any model adds light (no L-buffer when none does)."""
        return bool(self.light_layers)

    def target(self, samples: int = 0) -> Target:
        """The G-buffer target: every layer (L-buffer layers included) and a depth texture."""
        return Target(
            GBUFFER,
            colors=tuple(name for name, _ in self.layers),
            formats=tuple(fmt for _, fmt in self.layers),
            depth=True,
            samples=samples,
            relative="enclosing",
        )

    def bytes_per_pixel(self, samples: int = 0) -> int:
        """G-buffer plus L-buffer bytes per pixel (depth included); with multisampling also the per-pixel
        centre depth, edge flag and nearest depth (12 bytes) and the lights of every sample (a layer each)."""
        total = self.target(samples).bytes_per_pixel()
        if samples > 1:
            total += 12 + FORMATS[self.light_format][3] * len(self.light_layers) * samples
        return total

    def memory(self, size: tuple[int, int] = (1920, 1080), samples: int = 0) -> int:
        """Bytes of the G-buffer and L-buffer for a frame of ``size`` pixels."""
        return self.bytes_per_pixel(samples) * int(size[0]) * int(size[1])

    def describe(self, size: tuple[int, int] = (1920, 1080), samples: int = 0) -> str:
        """The layout as text: layers, formats, what each model stores where, memory at ``size``."""
        lines = [f"deferred buffers for models {', '.join(m.name for m in self.models) or '(none)'}:"]
        lines.append("  depth        depth24       4 B  window depth")
        for name, fmt in self.layers:
            what = _layer_contents(self, name)
            lines.append(f"  {name:<12} {fmt:<12} {FORMATS[fmt][3]:>2} B  {what}")
        if not self.has_lbuffer:
            lines.append("  (no L-buffer: no model adds light)")
        if samples > 1:
            lights = f"{len(self.light_layers) * samples} x {self.light_format}"
            lines.append(
                f"  with {samples} samples: the layers above per sample, a per-pixel centre depth and edge flag "
                f"(rg32f, 8 B) and nearest depth (4 B), the lights per sample ({lights})"
            )
        mib = self.memory(size, samples) / 2**20
        lines.append(
            f"  {self.bytes_per_pixel(samples)} B per pixel{f' ({samples} samples)' if samples else ''}: "
            f"{mib:.1f} MiB at {size[0]}x{size[1]}"
        )
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"BufferLayout({[m.name for m in self.models]}, {[n for n, _ in self.layers]})"


def _layer_contents(layout: BufferLayout, layer: str) -> str:
    parts: list[str] = ["normal (oct 12+12), material id (12), flags (4)"] if layer == "fixed" else []
    for m in layout.models:
        names = []
        for table in (layout.channels[m.number], layout.light[m.number]):
            for name, channels in table.items():
                comps = [c.location()[1] for c in channels if c.location()[0] == layer]
                if comps:
                    names.append(f"{name}[{''.join('rgba'[c] for c in comps)}]")
        if names:
            parts.append(f"{m.name}: {' '.join(names)}")
    return "; ".join(parts) if parts else "-"
