"""A material chart: one flat patch per kind of surface, the same lights, for comparing engines by colour.

:func:`material_chart` lays out patches facing an orthographic camera (so a
patch's colour is uniform and its mean is robust): Phong diffuse, specular
and shininess, a metallic x roughness grid of PBR materials, textured,
emissive, vertex-coloured, alpha-masked and blended surfaces, and the
appearance model's combination rules (a Color after a Material, a Material
after a PBRMaterial).  :func:`patch_means` reads the mean colour of each patch
from a rendered image.  The engine agreement test and the README's figure use
it; it is also a quick calibration picture for a new engine.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import omnirender as om

__all__ = ["material_chart", "patch_means", "CHART_PATCHES", "CHART_SIZE"]

#: Columns and rows of the chart.
COLUMNS, ROWS = 6, 3
#: The size the chart is laid out for (each patch is an 80 x 80 pixel cell).
CHART_SIZE = (COLUMNS * 80, ROWS * 80)


def _checker(n: int = 8, a: Any = (230, 200, 60), b: Any = (40, 90, 200), alpha: bool = False) -> np.ndarray:
    tiles = (np.indices((n, n)).sum(axis=0) % 2).astype(bool)
    img = np.zeros((n, n, 4), np.uint8)
    img[..., :3] = np.where(tiles[..., None], np.array(a, np.uint8), np.array(b, np.uint8))
    img[..., 3] = np.where(tiles, 255, 0) if alpha else 255
    return img


def _patches() -> list[tuple[str, list[Any]]]:
    """(name, appearance attributes) per patch, row by row."""
    checker = om.Texture(_checker(), filter="nearest", mipmap=False)
    cutout = om.Texture(_checker(alpha=True), filter="nearest", mipmap=False)
    return [
        ("phong red", [om.Material(diffuse=(0.8, 0.2, 0.2), ambient=(0.8, 0.2, 0.2))]),
        ("phong green", [om.Material(diffuse=(0.2, 0.7, 0.3))]),
        ("phong blue", [om.Material(diffuse=(0.2, 0.3, 0.9), ambient=(0.1, 0.1, 0.1))]),
        ("specular n=5", [om.Material(diffuse=(0.5, 0.5, 0.5), specular=(0.6, 0.6, 0.6), shininess=5)]),
        ("specular n=60", [om.Material(diffuse=(0.9, 0.5, 0.1), specular=(1, 1, 1), shininess=60)]),
        ("emissive phong", [om.Material(diffuse=(0.1, 0.1, 0.1), emission=(0.6, 0.3, 0.0))]),
        ("pbr m0 r0.3", [om.PBRMaterial(base_color=(0.8, 0.3, 0.3), metallic=0.0, roughness=0.3)]),
        ("pbr m0 r0.8", [om.PBRMaterial(base_color=(0.3, 0.8, 0.3), metallic=0.0, roughness=0.8)]),
        ("pbr m1 r0.3", [om.PBRMaterial(base_color=(0.9, 0.7, 0.3), metallic=1.0, roughness=0.3)]),
        ("pbr m1 r0.8", [om.PBRMaterial(base_color=(0.7, 0.7, 0.75), metallic=1.0, roughness=0.8)]),
        ("pbr textured", [om.PBRMaterial(base_color=(1, 1, 1), roughness=0.7, base_color_texture=checker)]),
        ("pbr emissive", [om.PBRMaterial(base_color=(0.05, 0.05, 0.05), emission=(0.2, 0.6, 0.9))]),
        ("color only", [om.Color(0.9, 0.6, 0.2)]),
        ("vertex colours", []),
        ("alpha mask", [om.PBRMaterial(base_color_texture=cutout, alpha_mode="mask", roughness=0.8)]),
        ("textured phong", [om.Material(diffuse=(1, 1, 1)), checker]),
        ("color after material", [om.Material(diffuse=(0.9, 0.1, 0.1)), om.Color(0.1, 0.3, 0.9)]),
        ("material after pbr", [om.PBRMaterial(base_color=(0.1, 0.1, 0.9)), om.Material(diffuse=(0.9, 0.3, 0.1))]),
    ]


#: Patch names in chart order (row by row).
CHART_PATCHES = tuple(name for name, _ in _patches())


def _quad(colors: bool) -> om.TriangleSet:
    v = np.array([[-0.4, -0.4, 0], [0.4, -0.4, 0], [0.4, 0.4, 0], [-0.4, 0.4, 0]], np.float64)
    c = np.array([[0.9, 0.2, 0.2], [0.2, 0.9, 0.2], [0.2, 0.2, 0.9], [0.9, 0.9, 0.2]]) if colors else None
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float64)
    return om.TriangleSet(v, [[0, 1, 2], [0, 2, 3]], normals=[[0, 0, 1]] * 4, colors=c, texcoords=uv)


def material_chart() -> om.Node:
    """The chart scene: 6 x 3 patches, one slanted directional light, the global ambient, a black background."""
    scene = om.Node("chart")
    scene.add(om.Camera.orthographic(eye=(0, 0, 5), center=(0, 0, 0), height=float(ROWS)))
    scene.add(om.Background((0.0, 0.0, 0.0)))
    scene.add(om.DirectionalLight(direction=(-0.35, -0.25, -1.0), intensity=0.85))
    for index, (name, attrs) in enumerate(_patches()):
        row, col = divmod(index, COLUMNS)
        x = col - (COLUMNS - 1) / 2
        y = (ROWS - 1) / 2 - row
        patch = scene.add(om.Node(name.replace(" ", "_").replace("=", "").replace(".", ""), [om.Translation(x, y, 0)]))
        for attr in attrs:
            patch.add(attr)
        patch.add(_quad(colors=name == "vertex colours"))
    return scene


def patch_means(image: Any, margin: int = 14) -> np.ndarray:
    """(patches, 3) mean sRGB colour of each patch's interior (``margin`` pixels of each cell left out)."""
    rgb = np.asarray(image.rgb if hasattr(image, "rgb") else image, np.float64)[..., :3]
    h, w = rgb.shape[:2]
    cw, ch = w / COLUMNS, h / ROWS
    out = []
    for index in range(len(CHART_PATCHES)):
        row, col = divmod(index, COLUMNS)
        # the quad is 0.8 of its cell; keep its middle
        x0, x1 = int(col * cw + 0.1 * cw + margin * cw / 80), int((col + 1) * cw - 0.1 * cw - margin * cw / 80)
        y0, y1 = int(row * ch + 0.1 * ch + margin * ch / 80), int((row + 1) * ch - 0.1 * ch - margin * ch / 80)
        out.append(rgb[y0:y1, x0:x1].reshape(-1, 3).mean(axis=0))
    return np.array(out)
