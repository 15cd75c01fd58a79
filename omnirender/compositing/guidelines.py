"""The renderer-tree guidelines of the compositing paper, checked on a tree before it is drawn.

:func:`check_tree` walks a tree and returns one :class:`TreeProblem` per
broken guideline (an empty list for a well-formed tree):

1. ``root``: the root is a renderer group (it owns the image the leaves merge into);
2. ``first-filter``: a filter is never a group's first child (a filter changes
   the image its predecessors made; first, it has nothing to work on);
3. ``only-filters``: a group has at least one child that is not a filter;
4. ``empty``: a group has children;
5. ``cycle``: no renderer is its own ancestor (a renderer shared by two
   groups is fine: trees may be DAGs);
6. ``peel-layers``: every renderer below a :class:`DepthPeelGroup` can draw
   depth-peeled layers (``draws_layers()``: scene renderers and groups of
   them; a volume or a filter cannot);
7. ``distance-pair``: a :class:`DistanceGroup` has exactly two children, the
   surface it colours and the reference it measures to, and neither is a
   filter.

Each problem names the path of the renderer (``DepthGroup/[1]LuminanceFilter``)
and what to change.  Only the tree's structure is judged; :func:`check_rules`
tests what each renderer does to the buffers (the four integration rules).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .renderer import Filter, Renderer, RendererGroup

__all__ = ["TreeProblem", "check_tree", "GUIDELINES"]

#: The guideline names :func:`check_tree` reports, in the order of the module docstring.
GUIDELINES = ("root", "first-filter", "only-filters", "empty", "cycle", "peel-layers", "distance-pair")


@dataclass(frozen=True)
class TreeProblem:
    """One broken guideline: its name, the renderer's path in the tree and the message (with the fix)."""

    guideline: str
    path: str
    message: str

    def __str__(self) -> str:
        return f"{self.path}: {self.message} [{self.guideline}]"


def check_tree(root: Renderer) -> list[TreeProblem]:
    """The guidelines ``root``'s tree breaks (see the module docstring), in tree order."""
    if not isinstance(root, Renderer):
        raise TypeError(f"check_tree: root must be an om.compositing.Renderer, got {type(root).__name__}")
    problems: list[TreeProblem] = []
    name = type(root).__name__
    if not isinstance(root, RendererGroup):
        problems.append(TreeProblem("root", name, f"the root is a {name}, not a renderer group; put it into one "
                                                  "(om.compositing.DepthGroup([...]))"))  # fmt: skip
    _walk(root, name, (), problems)
    return problems


def _walk(node: Renderer, path: str, ancestors: tuple[int, ...], problems: list[TreeProblem]) -> None:
    if id(node) in ancestors:
        problems.append(TreeProblem("cycle", path, "this renderer is its own ancestor; a tree must not loop"))
        return
    if not isinstance(node, RendererGroup):
        return
    children: tuple[Any, ...] = tuple(node.children)
    if not children:
        problems.append(TreeProblem("empty", path, "the group has no children; add renderers or remove it"))
        return
    if isinstance(children[0], Filter):
        problems.append(TreeProblem("first-filter", f"{path}/[0]{type(children[0]).__name__}",
                                    "a filter is the group's first child, so it has no image to filter; put it "
                                    "after the renderers whose output it changes"))  # fmt: skip
    if all(isinstance(child, Filter) for child in children):
        problems.append(TreeProblem("only-filters", path, "the group holds only filters; add a renderer before them"))
    _special(node, path, children, problems)
    for i, child in enumerate(children):
        _walk(child, f"{path}/[{i}]{type(child).__name__}", (*ancestors, id(node)), problems)


def _special(node: RendererGroup, path: str, children: tuple[Any, ...], problems: list[TreeProblem]) -> None:
    """The guidelines of the depth-peeling and distance groups."""
    from .distance import DistanceGroup
    from .peeling import DepthPeelGroup

    if isinstance(node, DepthPeelGroup):
        for i, child in enumerate(children):
            for where, leaf in _no_layers(child, f"{path}/[{i}]{type(child).__name__}", ()):
                problems.append(TreeProblem("peel-layers", where, f"a {type(leaf).__name__} cannot draw "
                                            "depth-peeled layers; draw it outside the DepthPeelGroup (e.g. "
                                            "DepthGroup([DepthPeelGroup([...]), it]))"))  # fmt: skip
    if isinstance(node, DistanceGroup):
        if len(children) != 2:
            message = f"a DistanceGroup has {len(children)} children; give two: the surface, then the reference"
            problems.append(TreeProblem("distance-pair", path, message))
        for i, child in enumerate(children):
            if isinstance(child, Filter) and i > 0:  # a first filter is reported as first-filter already
                problems.append(TreeProblem("distance-pair", f"{path}/[{i}]{type(child).__name__}",
                                            "a filter has no surface to measure; give a renderer"))  # fmt: skip


def _no_layers(node: Any, path: str, ancestors: tuple[int, ...]) -> list[tuple[str, Any]]:
    """(path, renderer) of the renderers below ``node`` (itself included) that cannot draw peeled layers."""
    if id(node) in ancestors:
        return []  # a cycle: reported as such
    if not isinstance(node, RendererGroup):
        return [] if node.draws_layers() else [(path, node)]
    if type(node).draws_layers is Renderer.draws_layers:  # a group that does not pass layers on
        return [(path, node)]
    found = []
    for i, child in enumerate(node.children):
        found += _no_layers(child, f"{path}/[{i}]{type(child).__name__}", (*ancestors, id(node)))
    return found
