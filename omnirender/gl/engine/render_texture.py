"""Chained pipelines: ``om.gl.RenderTexture(scene, camera, size)``, a texture whose image is a rendered scene.

A render texture is an ``om.Texture`` (a subclass), so it goes wherever a
texture goes: a material's image, a ``MultiTexture`` layer, a pass shader's
``Shader(textures=...)``.  Its image is ``scene`` seen through ``camera``
(None: the scene's own camera) at ``size`` pixels.  That is guacamole's
chained pipelines: a portal showing another scene, a security-camera screen,
a mirror-like view, screen-space refraction reading the last frame.

What the image means is the same for every engine: the picture the engine
itself makes of the pipeline's scene, as 8-bit display values like any
texture image.

* **GL** renders every pipeline the frame needs before the frame, once per
  frame, in dependency order (:mod:`.pipelines`); a pipeline whose scene
  uses its own texture reads its previous frame (black on the first); a
  cycle of two or more pipelines raises :class:`PipelineCycleError` naming it.
* **POV-Ray, Mitsuba, Radiance** render the pipeline's scene with themselves
  first (:meth:`RenderTexture.image_in`) and map that image like any texture;
  a self-reference reads the engine's previous image of it (black the first
  time), a cycle raises the same error.
* **Exporters** (glTF, the web page, RIB) and CPU texture work embed the GL
  rendering of the pipeline (:meth:`RenderTexture.image_array`).
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...attributes import Texture
from ...attributes._params import Param
from ...core import version_key
from ...core.camera import Camera

__all__ = ["RenderTexture", "PipelineCycleError", "OFFLINE_ENGINES", "pipeline_scene", "visit"]

#: The engine names offline engines pass to ``Texture.image_in`` -> their names in ``om.render``.
OFFLINE_ENGINES = {"POV-Ray": "povray", "MitsubaEngine": "mitsuba", "Radiance": "radiance"}
#: Largest side of a render texture.
MAX_SIDE = 4096


class PipelineCycleError(ValueError):
    """Render textures that need each other's image in the same frame (a cycle of two or more pipelines)."""


def _check_scene(owner: str, name: str, value: Any) -> Any:
    if not hasattr(value, "local_program"):
        raise ValueError(f"{owner}: {name} must be an om.Node (the scene the pipeline renders), got {value!r:.60}")
    return value


def _check_camera(owner: str, name: str, value: Any) -> Any:
    if value is not None and not isinstance(value, Camera):
        raise ValueError(f"{owner}: {name} must be an om.Camera or None (the scene's own), got {value!r:.60}")
    return value


def _check_size(owner: str, name: str, value: Any) -> tuple[int, int]:
    try:
        w, h = value
        ok = all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and 1 <= v <= MAX_SIDE for v in (w, h))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{owner}: {name} must be (width, height) in pixels, 1..{MAX_SIDE}, got {value!r}")
    return (int(w), int(h))


def _check_label(owner: str, name: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ValueError(f"{owner}: {name} must be a non-empty string, got {value!r}")
    return value


class RenderTexture(Texture):
    """A texture whose image is ``scene`` rendered through ``camera`` at ``size`` (see the module docs).

    ``name`` labels the pipeline in messages and pass reports (default: the
    scene's name).  Sampling parameters are an ``om.Texture``'s; the default
    wrap is ``"clamp"`` and there are no mipmaps (a new image every frame).
    """

    __slots__ = ("_scene", "_camera", "_size", "_name", "_offline")
    _transient = {"_offline": dict}
    #: The image is rendered by a pipeline, not read (engines that upload images check this).
    rendered = True
    category = Texture  # it replaces the texture in effect, as any om.Texture
    scene = Param(_check_scene, "the scene the pipeline renders")
    camera = Param(_check_camera, "its camera (None: the scene's own)")
    size = Param(_check_size, "image size (width, height) in pixels")
    name = Param(_check_label, "the pipeline's name in messages")

    def __init__(
        self,
        scene: Any,
        camera: Camera | None = None,
        size: Sequence[int] = (256, 256),
        *,
        name: str | None = None,
        wrap: str = "clamp",
        filter: str = "linear",
        mipmap: bool = False,
        uv_set: int = 0,
        offset: Sequence[float] = (0.0, 0.0),
        scale: Sequence[float] = (1.0, 1.0),
        rotation: float = 0.0,
    ) -> None:
        object.__setattr__(self, "_offline", {})
        super().__init__(
            np.zeros((1, 1, 4), np.uint8), wrap=wrap, filter=filter, mipmap=mipmap, uv_set=uv_set,
            offset=offset, scale=scale, rotation=rotation,
        )  # fmt: skip
        self.scene = scene
        self.camera = camera
        self.size = size
        self.name = name if name is not None else f"RenderTexture({scene.name})"

    def parameters(self) -> dict[str, Any]:
        out = {"scene": self._scene, "camera": self._camera, "size": self._size, "name": self._name}
        params = super().parameters()
        params.pop("image")
        return {**out, **params}

    def has_alpha(self) -> bool:
        """A rendered image is opaque (the pipeline clears to its scene's opaque background)."""
        return False

    def content_key(self) -> tuple:
        """What the image depends on directly: the scene's and camera's versions, the size."""
        return (version_key(self._scene), version_key(self._camera), self._size)

    # -- engines that render the pipeline themselves -------------------------------------------
    def image_array(self) -> np.ndarray:
        """The GL engine's image of the pipeline (for exporters and CPU texture work); cached per version."""
        return self.rendered_image("gl")

    def image_in(self, engine: str, node_path: str) -> np.ndarray:
        """The image ``engine`` (an offline engine's name) makes of the pipeline: it renders the scene itself."""
        return self.rendered_image(OFFLINE_ENGINES.get(engine, "gl"))

    def rendered_image(self, engine: str) -> np.ndarray:
        """The pipeline rendered by ``engine`` (an ``om.render`` name), cached until the scene or camera changes."""
        cached = self._offline.get(engine)
        key = self.content_key()
        stack = _stack()
        if visit(stack, self) == "self":  # this pipeline's scene shows this pipeline: the previous image
            return cached[1] if cached is not None else black(self._size)
        if cached is not None and cached[0] == key:
            return cached[1]
        from ...render import render

        stack.append(self)
        try:
            image = render(pipeline_scene(self), engine=engine, size=self._size)
        finally:
            stack.pop()
        pixels = np.ascontiguousarray(image.array)
        pixels.setflags(write=False)
        self._offline[engine] = (key, pixels)
        return pixels


def black(size: tuple[int, int]) -> np.ndarray:
    """The image of a pipeline that has not been drawn yet: opaque black."""
    out = np.zeros((size[1], size[0], 4), np.uint8)
    out[..., 3] = 255
    out.setflags(write=False)
    return out


def pipeline_scene(texture: RenderTexture) -> Any:
    """The scene a pipeline renders: its camera first (so it is the one declared), then the scene."""
    if texture.camera is None:
        return texture.scene
    from ...scene import Node

    return Node.transient([texture.camera, texture.scene], name=texture.name)  # the scene keeps its parents


def visit(stack: list[RenderTexture], texture: RenderTexture) -> str:
    """Where ``texture`` stands while the pipelines on ``stack`` are being rendered (innermost last).

    ``"self"``: it is the one being rendered (it reads its previous image); ``"new"``: it is not on the
    stack; a texture deeper in the stack is a cycle: :class:`PipelineCycleError` names it.
    """
    for i, other in enumerate(stack):
        if other is texture:
            if i == len(stack) - 1:
                return "self"
            names = " -> ".join(t.name for t in (*stack[i:], texture))
            raise PipelineCycleError(
                f"RenderTexture: the pipelines {names} need each other's image in the same frame (a cycle); "
                "break it: let one of them show another camera or scene, or a copy of the texture"
            )
    return "new"


_local = threading.local()


def _stack() -> list[RenderTexture]:
    stack = getattr(_local, "stack", None)
    if stack is None:
        stack = _local.stack = []
    return stack
