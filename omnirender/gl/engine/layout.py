"""The per-instance data of a draw item, as a named layout.

Every draw item carries one float32 *row*: its model matrix and its surface
(colour, Phong or PBR parameters, emission, highlight, point size).  The row
is addressed by field name (``ROW.slice("color")``, ``ROW.at("color", 3)``
for the alpha), never by raw offsets.  A batch sends the GPU only the fields
its program variant reads (``ROW.subset(...)``): a Phong variant with one
shared material gets model and colour per instance, a PBR variant its
roughness and metallic, and nobody pays for the highlight unless something is
highlighted.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

__all__ = ["Field", "InstanceLayout", "ROW", "SHADING_MODELS", "PHONG", "PBR", "UNLIT", "shading_model"]

#: Shading models (the ``model`` component of the ``emission`` field, and the MODEL shader define).
PHONG, PBR, UNLIT = 0, 1, 2
SHADING_MODELS = {"phong": PHONG, "pbr": PBR, "unlit": UNLIT}


def shading_model(appearance_model: str, description: Any) -> int:
    """The shading model a surface row holds: the material description's (the deferred pipeline's), else
    :data:`PBR` for a metallic-roughness appearance (``Appearance.model``), else :data:`PHONG`."""
    if description is not None:
        return description.model.number
    return PBR if appearance_model == "pbr" else PHONG


class Field(NamedTuple):
    """A named run of floats in the row and the GLSL instance attribute that receives it."""

    name: str
    size: int
    attribute: str
    #: names of the components (documentation and ``at``)
    components: tuple[str, ...]


class InstanceLayout:
    """Fields in order, with their offsets into the row."""

    def __init__(self, fields: tuple[Field, ...]) -> None:
        self.fields = fields
        self.offsets: dict[str, int] = {}
        offset = 0
        for f in fields:
            if len(f.components) not in (1, f.size):
                raise ValueError(f"layout field {f.name}: {len(f.components)} component names for {f.size} floats")
            self.offsets[f.name] = offset
            offset += f.size
        #: floats per row
        self.stride = offset
        self._by_name = {f.name: f for f in fields}
        self._names = tuple(f.name for f in fields)

    def field(self, name: str) -> Field:
        return self._by_name[name]

    def slice(self, name: str) -> slice:
        """Where field ``name`` lies in a row."""
        start = self.offsets[name]
        return slice(start, start + self._by_name[name].size)

    def at(self, name: str, component: int | str) -> int:
        """The row index of one component of a field (by position or component name)."""
        f = self._by_name[name]
        index = f.components.index(component) if isinstance(component, str) else int(component)
        return self.offsets[name] + index

    def subset(self, names: tuple[str, ...]) -> InstanceLayout:
        """The layout of only ``names`` (in this layout's order), e.g. what one program variant reads."""
        keep = set(names)
        unknown = keep - set(self._by_name)
        if unknown:
            raise KeyError(f"instance layout has no field {sorted(unknown)}; fields: {list(self._by_name)}")
        return InstanceLayout(tuple(f for f in self.fields if f.name in keep))

    def columns(self, parent: InstanceLayout) -> np.ndarray:
        """Indices of this layout's floats in rows of ``parent`` (to pack rows for the GPU)."""
        return np.concatenate([np.arange(parent.offsets[f.name], parent.offsets[f.name] + f.size) for f in self.fields])

    def vertex_format(self) -> tuple[str, tuple[str, ...]]:
        """moderngl buffer format (per instance) and the attribute names, for ``ctx.vertex_array``."""
        fmt = " ".join(f"{f.size}f" for f in self.fields) + "/i"
        return fmt, tuple(f.attribute for f in self.fields)

    def names(self) -> tuple[str, ...]:
        return self._names

    def __repr__(self) -> str:
        return f"InstanceLayout({', '.join(f'{f.name}[{f.size}]' for f in self.fields)})"


#: The full row every draw item carries.
ROW = InstanceLayout(
    (
        Field("model", 16, "i_model", ("column-major 4x4",)),
        Field("color", 4, "i_color", ("r", "g", "b", "alpha")),  # linear base colour
        Field("specular", 4, "i_spec", ("r", "g", "b", "shininess")),  # Phong
        Field("emission", 4, "i_emis", ("r", "g", "b", "model")),  # model: PHONG, PBR or UNLIT
        Field("ambient", 4, "i_amb", ("r", "g", "b", "follows_color")),  # Phong; 1: ambient = base colour
        Field("pbr", 4, "i_pbr", ("roughness", "metallic", "material", "unused")),  # material: deferred table id
        Field("highlight", 4, "i_hl", ("r", "g", "b", "on")),
        Field("point", 4, "i_point", ("size", "unused", "unused", "unused")),
    )
)
