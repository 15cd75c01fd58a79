"""Planar mirrors in the GL engine: the stencil technique of the VRS paper.

Shapes under an ``om.Mirror`` are drawn as usual by the frame's technique;
then, for each mirror in turn, four passes (:class:`Mirrors`):

1. ``mark``: the mirror's visible pixels (depth test ``lequal`` against the
   drawn scene) set stencil bit 1;
2. ``open``: where the bit is set, depth is reset to the far plane and the
   colour to the background (what the mirror shows where nothing is reflected);
3. ``reflection``: the scene mirrored about the mirror's plane (the camera
   times the reflection, front faces turned), its mirror shapes left out
   (nesting depth 1), clipped to the mirror's front side, only where the bit
   is set: lighting and shadow maps are those of the real scene; the shapes
   under other techniques (line styles, shadow volumes...) are drawn plainly;
4. ``surface``: the mirror blended over its reflection with weight
   ``1 - reflectance``, restoring its depth and clearing the bit.

Several mirrors work one after the other.  Transparent shapes and overlays in
front of a mirror are drawn before it (the frame's technique drew them), so
the mirror stage covers them: keep translucent shapes away from mirrors.  The
engine needs a stencil buffer (it has one wherever the driver offers
depth-stencil framebuffers).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ..engine.attributes import Blend, ColorMask, DepthMask, DepthTest, StencilOp, StencilTest
from ..engine.layout import ROW
from ..engine.passes import Pass, Shader
from ..engine.stages import FrameStage
from ..engine.state import MirrorState, not_mirror
from ..engine.technique import GLTechnique

__all__ = ["Mirrors", "MirrorStage", "mirror_items", "reflection_matrix"]

_MODEL = ROW.slice("model")
_BIT = 1

_OPEN = "void pass_fragment(inout vec4 color, vec3 P, vec3 N) { gl_FragDepth = 1.0; }"
_CLIP = """uniform vec4 u_mirror_plane;   // world plane of the mirror, positive on the camera's side
void pass_fragment(inout vec4 color, vec3 P, vec3 N) {
    vec3 W = (u_eye_to_world * vec4(P, 1.0)).xyz;
    if (dot(u_mirror_plane.xyz, W) + u_mirror_plane.w < 0.0) discard;
}"""
_SURFACE = (
    "uniform float u_mirror_keep; void pass_fragment(inout vec4 color, vec3 P, vec3 N) { color.a = u_mirror_keep; }"
)


def reflection_matrix(plane: np.ndarray) -> np.ndarray:
    """The 4x4 reflection about the world plane (a, b, c, d) (unit normal)."""
    n, d = np.asarray(plane[:3], np.float64), float(plane[3])
    m = np.eye(4)
    m[:3, :3] -= 2.0 * np.outer(n, n)
    m[:3, 3] = -2.0 * d * n
    return m


def mirror_items(items: list[Any]) -> list[tuple[Any, _Only]]:
    """The opaque mesh items drawn under an ``om.Mirror``, one per mirror, with their pass predicates."""
    out: dict[_Only, Any] = {}
    for it in items:
        if it.state.kind == "mesh" and not it.transparent and not not_mirror(it):
            out.setdefault(_Only(it), it)
    return [(item, only) for only, item in out.items()]


class _Only:
    """Pass predicate: the items of one mirror (its node, geometry and state).

    Compared by value, so the filtered batches cached for it survive
    recompiles that only move things (in-place updates release them where
    items changed).  Mirror shapes of one geometry in one node under the same
    state are one mirror: give each mirror its own node.
    """

    __slots__ = ("node", "geometry", "state")

    def __init__(self, item: Any) -> None:
        self.node, self.geometry, self.state = item.node, item.geometry, item.state

    def __call__(self, item: Any) -> bool:
        return item.geometry is self.geometry and item.state is self.state and item.node is self.node

    def _key(self) -> tuple[int, int, int]:
        return (id(self.node), id(self.geometry), id(self.state))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Only) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


class Mirrors(GLTechnique):
    """The mirror passes of one frame (the engine runs them after its technique)."""

    __slots__ = ("descriptions",)

    def __init__(self, descriptions: list[Pass]) -> None:
        super().__init__(passes=max(len(descriptions), 1))
        object.__setattr__(self, "descriptions", tuple(descriptions))

    def prepare_pass(self, engine: Any) -> None:
        if self.descriptions:
            engine.set_pass(self.descriptions[engine.current_pass])

    @classmethod
    def plan(cls, mirrors: list[tuple[Any, _Only]], view: np.ndarray, proj: np.ndarray, background: Any) -> Mirrors:
        """The passes for ``mirrors`` ((item, its predicate) pairs) seen with ``view`` and ``proj``."""
        eye = np.linalg.inv(view)[:3, 3]
        passes: list[Pass] = []
        marked = StencilTest(True, "always", _BIT, _BIT)
        inside = StencilTest(True, "equal", _BIT, _BIT)
        for k, (item, only) in enumerate(mirrors):
            reflectance, normal, offset = item.state.raster[MirrorState.index]
            model = item.row[_MODEL].reshape(4, 4).T.astype(np.float64)
            plane = np.linalg.inv(model).T @ np.array([*normal, -offset])
            plane /= np.linalg.norm(plane[:3])
            if plane[:3] @ eye + plane[3] < 0.0:
                plane = -plane  # positive on the camera's side
            name = f"mirror[{k}]"
            flat = Shader(flat_color=(0.0, 0.0, 0.0, 1.0))
            common = {"items": "opaque", "select": only, "scopes": "items", "source": "scene"}
            passes.append(Pass(f"{name}.mark", **common, shader=flat, state=(
                marked, StencilOp("keep", "keep", "replace", _BIT), ColorMask(False, False, False, False),
                DepthMask(False), DepthTest(True, "lequal"))))  # fmt: skip
            passes.append(Pass(f"{name}.open", **common, shader=Shader(flat_color=background, fragment=_OPEN),
                               state=(inside, StencilOp(write_mask=0), DepthMask(True),
                                      DepthTest(True, "always"))))  # fmt: skip
            passes.append(
                Pass(
                    f"{name}.reflection",
                    items=("opaque", "transparent"),  # 2D overlays belong to the screen, not the mirror world
                    select=not_mirror,
                    scopes="items",  # nested techniques' items drawn plainly: effects stay out of reflections
                    source="scene",
                    camera=(view @ reflection_matrix(plane), proj),
                    front_face="cw",
                    state=(inside, StencilOp(write_mask=0)),
                    shader=Shader(fragment=_CLIP, uniforms={"u_mirror_plane": tuple(plane)}),
                )
            )
            passes.append(Pass(f"{name}.surface", **common, shader=Shader(
                fragment=_SURFACE, uniforms={"u_mirror_keep": 1.0 - reflectance}), state=(
                inside, StencilOp("keep", "keep", "zero", _BIT), Blend(), DepthMask(True),
                DepthTest(True, "always"))))  # fmt: skip
        return cls(passes)


class MirrorStage(FrameStage):
    """The frame stage of the planar mirrors, after the frame technique (it reflects what that drew).

    It forgets nothing when placements change (no :meth:`changed`): the engine's render index finds the
    mirrors once per draw list, and the planes are read from the rows every frame.
    """

    name = "mirrors"

    def __init__(self) -> None:
        self._warned = False

    def replayable(self, engine: Any) -> bool:
        """What it draws follows the draw list, lights and settings; a frame that draws anything here is
        not recorded (its technique, target and shadow uniforms taint the frame plan)."""
        return True

    def follows_rows(self, engine: Any) -> bool:
        """A recorded frame drew no mirror (mirror planes come from rows, but such frames are not recorded)."""
        return True

    def draw(self, frame: Any, root: Any) -> int:
        engine = frame.engine
        if engine.stereo is not None:
            if engine.root_scope is not None and not self._warned and engine.index.mirror_items():
                self._warned = True
                warnings.warn("GLEngine: mirrors are drawn as plain surfaces in stereo frames (the mirror "
                              "stage reflects one eye)", stacklevel=4)  # fmt: skip
            return 0
        mirrors = engine.index.mirror_items() if engine.root_scope is not None else []
        if not mirrors:
            return 0
        if not engine.has_stencil or engine.pushed_targets:
            if not self._warned:
                self._warned = True
                warnings.warn("GLEngine: mirrors need the engine's own stencil buffer; they are drawn as plain "
                              "surfaces here", stacklevel=4)  # fmt: skip
            return 0
        state = frame.state
        technique = Mirrors.plan(mirrors, state.view, state.proj, engine.clear_color(state.background))
        return frame.run(technique, root, item_level=False)
