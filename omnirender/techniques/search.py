"""Attribute search: what the engine applies at a node path.

The :class:`AttributeSearchEngine` evaluates the scene without evaluating any
shape and captures the rendering context at the end of the node's contents
(just before the node's own attributes are undone, or in the engine's
``on_leave`` hook if it has none): the top attribute of every mono category and the active members of
every poly category, including the pre-evaluated lights (after any
``LightSwitch``) and the pre-evaluated camera.  The ``Transform`` category maps
to the accumulated model matrix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.camera import Camera
from ..core.light import Light
from ..core.transform import Transform
from .base import AnalysisEngine, check_scene, evaluate_in_place

__all__ = ["AttributeSearch", "AttributeSearchEngine", "attribute_search"]


@dataclass
class AttributeSearch:
    """Result of :func:`attribute_search`: ``mono`` {category: top attribute}, ``poly`` {category: [attributes]}."""

    path: str
    mono: dict[type, Any] = field(default_factory=dict)
    poly: dict[type, list[Any]] = field(default_factory=dict)

    def __getitem__(self, category: type) -> Any:
        """The mono attribute or poly list of ``category`` (KeyError when none applies)."""
        if category in self.mono:
            return self.mono[category]
        return self.poly[category]

    def __contains__(self, category: type) -> bool:
        return category in self.mono or category in self.poly

    def __str__(self) -> str:
        """One line per category, named by class, so ``print(om.attribute_search(...))`` is readable."""
        lines = [f"attributes at {self.path}:"]
        for category, value in self.mono.items():
            if isinstance(value, np.ndarray):  # the Transform category: the accumulated model matrix
                text = np.array2string(value, precision=4, suppress_small=True, separator=", ")
                text = text.replace("\n", "\n" + " " * (len(category.__name__) + 4))
            else:
                text = repr(value)
            lines.append(f"  {category.__name__}: {text}")
        for category, values in self.poly.items():
            lines.append(f"  {category.__name__} ({len(values)}): " + ", ".join(repr(v) for v in values))
        return "\n".join(lines)


class AttributeSearchEngine(AnalysisEngine):
    """Captures the context at the end of the contents of the node at ``path`` (its first-parent occurrence).

    The node is the engine's scope (see :class:`AnalysisEngine`): the context
    is captured at the first pop/remove made directly in it (its own
    attributes being undone) or, when it has none, when it is left
    (``on_leave``), where the context equals the one its shapes saw.
    """

    service = "attribute.search"

    def __init__(self, path: str, *, mask: Any = None) -> None:
        super().__init__(mask=mask, on_missing="skip")
        self.path = path
        self.result: AttributeSearch | None = None

    def accepts(self, shape: Any) -> bool:
        return False  # shapes are never evaluated: nothing is simplified or drawn

    def _capture(self) -> None:
        if self.result is not None:
            return
        result = AttributeSearch(self.path)
        ctx = self.context
        for category in ctx.categories():
            items = ctx.poly(category)
            if items:
                result.poly[category] = list(items)
            elif category is not Transform and ctx.mono(category) is not None:
                result.mono[category] = ctx.mono(category)
        result.mono[Transform] = np.array(self.model_matrix())
        lights: list[Any] = []
        for light, _ in self.lights():
            if not any(light is seen for seen in lights):
                lights.append(light)
        if lights:
            result.poly[Light] = lights
        else:
            result.poly.pop(Light, None)
        if self.camera is not None and Camera not in result.mono:
            result.mono[Camera] = self.camera[0]
        self.result = result

    def pop(self, category: type) -> Any:
        if self.scope_level == 1:
            self._capture()
        return super().pop(category)

    def remove(self, attribute: Any) -> None:
        if self.scope_level == 1:
            self._capture()
        super().remove(attribute)

    def leave_scope(self, node: Any) -> None:
        self._capture()


def attribute_search(scene: Any, path: str, mask: str | None = None) -> AttributeSearch:
    """What the engine applies to the shapes at ``path``: ``.mono`` and ``.poly`` by category.

    ``path`` is absolute (``"/scene/body"``) or relative to ``scene``.  Raises
    KeyError naming the closest existing prefix when there is no such node, and
    ValueError when the node is masked out.
    """
    check_scene("attribute_search", scene)
    if not hasattr(scene, "_compile_node"):
        raise TypeError(
            f"attribute_search: scene must be an om.Node (paths name its nodes), got {type(scene).__name__}"
        )
    node = scene[path]
    engine = AttributeSearchEngine(node.path, mask=mask)
    evaluate_in_place(engine, node, mask)
    if engine.result is None:
        raise ValueError(
            f"attribute_search: node {node.path} is not evaluated (its groups do not match the mask {mask!r}); "
            f"pass a mask that selects it"
        )
    return engine.result
