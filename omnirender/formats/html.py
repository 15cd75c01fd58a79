"""A self-contained web page of a scene (``om.export(scene, "scene.html")``).

One HTML file that opens offline in any browser with WebGL: the scene as a
base64 glTF binary (the glTF exporter's, so the group mask, materials and
textures are the same), the page script with three.js, GLTFLoader and
OrbitControls inlined (``assets/three_viewer.min.js``, built from
``tools/web-viewer`` by its pinned ``build.sh`` with npm and esbuild and
committed, so users need no Node; three.js is MIT-licensed and its notice is
kept in the bundle and in ``assets/three.LICENSE``), and a few settings: the
background colour, the ambient light, the orbit distance of the scene's
camera.

Lights: glTF lights are physical (``KHR_lights_punctual``: point lights fall
off with the inverse square of the distance) and omnirender's follow OpenGL
(no fall-off unless the light has attenuation).  The page therefore converts
each light with the attenuation the glTF exporter keeps in its ``extras``:
intensities are multiplied by pi (three.js divides a Lambertian albedo by pi)
and a point or spot light falls off with the exponent of its attenuation (none
for the default ``constant=1``), so the page is about as bright as the other
engines' pictures.  ``om.RectLight``/``om.DiscLight`` (a spot with the area light in its
extras in the glTF) become three.js ``RectAreaLight``s of the light's radiance (a disc a
square of its area); three.js draws no shadows for them and lights only physically based
materials with them, so a page with area lights shows Phong materials as
``MeshStandardMaterial`` of the Phong exponent's roughness.  Mouse: left drag orbits around the camera's centre, right
drag pans, the wheel zooms.
"""

from __future__ import annotations

import base64
import html
import json
import os
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from ..attributes.environment import DEFAULT_BACKGROUND  # the page background without an om.Background
from ..fileio import atomic_write
from .gltf.writer import build

__all__ = ["export", "page", "ASSETS", "DEFAULT_BACKGROUND"]

#: The committed bundle and three.js's licence notice.
ASSETS = Path(__file__).parent / "assets"


@cache
def _bundle() -> str:
    path = ASSETS / "three_viewer.min.js"
    try:
        script = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RuntimeError(
            f"the web viewer bundle {path} is missing from this installation; rebuild it with "
            "tools/web-viewer/build.sh (npm) or reinstall omnirender"
        ) from None
    return script.replace("</script", "<\\/script")  # never ends the inline script early


def _background(engine: Any) -> list[float]:
    """The scene's background colour (RGBA display values) or :data:`DEFAULT_BACKGROUND`."""
    color = engine.background.color if engine.background is not None else DEFAULT_BACKGROUND
    return [min(max(float(c), 0.0), 1.0) for c in (*color, 1.0)[:4]]


def _settings(glb: bytes, engine: Any) -> dict[str, Any]:
    distance = 1.0
    if engine.camera is not None:
        camera, world = engine.camera
        eye, center = (np.asarray(world) @ np.array([*p, 1.0]) for p in (camera.eye, camera.center))
        distance = float(np.linalg.norm(center[:3] / center[3] - eye[:3] / eye[3]))
    ambient = engine.gltf.doc.get("extras", {}).get("ambient_light", [0.0, 0.0, 0.0])
    return {
        "glb": base64.b64encode(glb).decode("ascii"),
        "background": _background(engine),
        "ambient": [float(a) for a in ambient],
        "distance": distance,
    }


def page(
    scene: Any,
    *,
    size: tuple[int, int] = (960, 720),
    mask: str | None = None,
    title: str | None = None,
    on_missing: str = "raise",
) -> str:
    """The HTML text of the page (see the module docs); ``size`` gives the camera's aspect in the glTF."""
    # the page converts omnirender's light units itself (its attenuation in the lights' extras)
    glb, engine = build(scene, size=size, on_missing=on_missing, mask=mask, physical_lights=False)
    _warn_splats(engine.gltf.doc)
    settings = json.dumps(_settings(glb, engine), separators=(",", ":"))
    name = title if title is not None else getattr(scene, "name", "scene")
    r, g, b = (round(255 * c) for c in _background(engine)[:3])
    return _TEMPLATE.format(
        title=html.escape(str(name)),
        background=f"rgb({r}, {g}, {b})",
        bundle=_bundle(),
        settings=settings.replace("</", "<\\/"),
    )


def _warn_splats(doc: dict[str, Any]) -> None:
    """Say that the page shows Gaussian splats as the glTF extension's fallback point cloud, and why.

    three.js 0.187 has a ``GaussianSplat`` object (``examples/jsm/objects``, with a ``KHR_gaussian_splatting``
    loader plugin) but it renders only with ``WebGPURenderer`` (``three/webgpu``, TSL node materials, a GPU
    counting sort in compute shaders); the page uses ``WebGLRenderer``, which opens offline in every browser
    with WebGL.  Without the plugin, three.js draws a splat primitive as the extension's fallback: its
    ``POINTS`` with ``COLOR_0`` (the DC colour and the opacity), one pixel each.
    """
    count = 0
    for mesh in doc.get("meshes", []):
        for prim in mesh.get("primitives", []):
            if "KHR_gaussian_splatting" in prim.get("extensions", {}):
                count += int(doc["accessors"][prim["attributes"]["POSITION"]]["count"])
    if count:
        import warnings

        warnings.warn(
            f"web page: its {count:,} Gaussian splats are shown as the KHR_gaussian_splatting fallback point "
            "cloud (one point per splat with its base colour and opacity): three.js 0.187's GaussianSplat renders "
            "only with WebGPURenderer and this page uses WebGLRenderer; render splats with engine='gl', or export "
            "a .glb for a splat viewer",
            stacklevel=4,
        )


def export(scene: Any, path: str | os.PathLike[str], **options: Any) -> None:
    """Write the page of ``scene`` to ``path`` atomically (options: see :func:`page`)."""
    text = page(scene, **options)
    with atomic_write(path, "w") as fh:
        fh.write(text)


_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="omnirender">
<title>{title}</title>
<style>html, body {{ margin: 0; height: 100%; overflow: hidden; background: {background}; }}
#omnirender {{ width: 100%; height: 100%; }} canvas {{ display: block; }}</style>
</head>
<body>
<div id="omnirender"></div>
<!-- three.js (https://threejs.org) is MIT-licensed: its notice is the @license comment in the script -->
<script>{bundle}</script>
<script>OmniRenderViewer.show(document.getElementById("omnirender"), {settings});</script>
</body>
</html>
"""
