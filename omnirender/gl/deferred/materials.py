"""The material table: every material description a frame uses, as rows of a float texture.

A G-buffer pixel stores the *id* of its material description (12 bits), not the description's
values: a row of this table holds the shading model number and the parameter values (one vec4 per
parameter), which the lighting and shading stages read with ``texelFetch``.  Built-in materials
become rows too: a Phong material's specular colour and shininess (its diffuse colour, ambient and
emission are per pixel or consumed by the geometry pass), one row for every PBR material (all its
values are per pixel).  The compiler asks for the id when it builds a draw item's row
(``ROW "pbr"``'s ``material`` component), so instances of one batch may have different materials.

Ids are kept for the engine's life; when 4095 are in use the table starts again and the engine
recompiles (ids of old frames are gone then).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .models import PBR, PHONG, MaterialDescription

__all__ = ["MaterialTable", "CAPACITY"]

#: Material ids a frame can use (12 bits; id 0 marks pixels where nothing was drawn).
CAPACITY = 4095


class MaterialTable:
    """Material descriptions by id (model number and packed parameters), uploaded as a texture when changed."""

    def __init__(self) -> None:
        self._ids: dict[tuple[int, bytes], int] = {}
        self._rows: list[tuple[int, np.ndarray]] = [(-1, np.zeros(0, np.float32))]
        #: bumped when a row is added (the texture is uploaded again)
        self.version = 0
        #: bumped when the table starts again (every id handed out before is void)
        self.generation = 0
        self._texture: Any = None
        self._uploaded: tuple[int, int] | None = None
        #: (shading model, specular, shininess) of built-in materials -> (generation, id): an appearance's id
        #: without packing its values again (a replaced Material resolves one each frame)
        self._builtin: dict[tuple, tuple[int, int]] = {}

    def __len__(self) -> int:
        return len(self._rows) - 1

    def index(self, number: int, packed: np.ndarray) -> int:
        """The id of the description (model ``number``, ``packed`` parameter values), added when new."""
        key = (int(number), packed.tobytes())
        found = self._ids.get(key)
        if found is not None:
            return found
        if len(self._rows) > CAPACITY:
            self._ids.clear()
            del self._rows[1:]
            self.generation += 1
        self._rows.append((int(number), np.asarray(packed, np.float32)))
        self._ids[key] = len(self._rows) - 1
        self.version += 1
        return len(self._rows) - 1

    def for_appearance(self, app: Any, description: MaterialDescription | None) -> int:
        """The id of a resolved appearance (``attributes.surface.Appearance``), or of ``description``."""
        if description is not None:
            return self.index(description.model.number, description.packed)
        key = ("pbr",) if app.model == "pbr" else ("phong", app.specular, app.shininess)
        found = self._builtin.get(key)
        if found is not None and found[0] == self.generation:
            return found[1]
        if app.model == "pbr":
            found_id = self.index(PBR.number, PBR.pack({}))
        else:
            values = {"specular": app.specular, "shininess": app.shininess}
            found_id = self.index(PHONG.number, PHONG.pack(values, linear=True))
        if len(self._builtin) > 4096:
            self._builtin.clear()
        self._builtin[key] = (self.generation, found_id)
        return found_id

    def data(self) -> np.ndarray:
        """(rows, width, 4) float32: column 0 holds (model number, 0, 0, 0), then one vec4 per parameter."""
        width = 1 + max((len(p) // 4 for _, p in self._rows), default=0)
        out = np.zeros((len(self._rows), width, 4), np.float32)
        for i, (number, packed) in enumerate(self._rows):
            out[i, 0, 0] = number
            if packed.size:
                out[i, 1 : 1 + packed.size // 4] = packed.reshape(-1, 4)
        return out

    def texture(self, ctx: Any) -> Any:
        """The table as an RGBA32F texture (rows = ids), uploaded again when rows were added."""
        state = (self.version, self.generation)
        if self._texture is not None and self._uploaded == state:
            return self._texture
        data = self.data()
        h, w = data.shape[:2]
        if self._texture is not None and self._texture.size == (w, h):
            self._texture.write(data.tobytes())
        else:
            if self._texture is not None:
                self._texture.release()
            self._texture = ctx.texture((w, h), 4, data.tobytes(), dtype="f4")
            self._texture.filter = (ctx.NEAREST, ctx.NEAREST)
        self._uploaded = state
        return self._texture

    def release(self) -> None:
        if self._texture is not None:
            self._texture.release()
            self._texture = None
            self._uploaded = None
