"""Light proxies: the geometry each light of the deferred lighting pass is drawn as.

* point lights: spheres of the light's reach (``PointLight.reach()``: where its contribution
  falls below its ``threshold``), drawn as the back faces of a mesh that encloses the sphere;
* spot lights: cones of that length around the cut-off (spheres when the cut-off is wider than
  60 degrees);
* directional lights, point or spot lights without attenuation, rectangle and disc lights: one
  full-screen triangle each;
* ambient light needs no pass: the geometry pass adds it (the visibility stage has the ambient
  reflectance at hand there).

Lights of one kind and proxy are one instanced draw: per instance the proxy's matrix (unit mesh to
eye space) and the light's eye-space data.  Proxies are drawn as back faces with depth clamping, so
a camera inside a proxy still covers its pixels once; pixels whose surface point lies beyond the
light's reach or outside a spot's cone are discarded before any lighting code (culled against the
G-buffer depth).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...attributes.photometry import HEADLIGHT

__all__ = ["LightTable", "proxy_meshes", "STRIDE", "FULLSCREEN"]

#: Floats per light instance: proxy matrix (16), position, diffuse + reach, specular, attenuation, spot, extra,
#: an area light's half axes (u with the shape, v with two-sidedness).
STRIDE = 48
#: Instance attribute names and sizes, in buffer order.
ATTRIBUTES = (("i_proxy", 16), ("i_lpos", 4), ("i_ldiff", 4), ("i_lspec", 4), ("i_latt", 4), ("i_lspot", 4),
              ("i_lextra", 4), ("i_larea_u", 4), ("i_larea_v", 4))  # fmt: skip
FULLSCREEN = "fullscreen"
#: Spots wider than this are drawn as spheres (a cone's base would grow without bound).
MAX_CONE_CUTOFF = 60.0
_SEGMENTS = 16
_FAR = 3.0e38  # "no reach limit" in a float attribute


def proxy_meshes() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """(positions, triangle indices) of the unit proxies: ``sphere`` encloses the unit sphere, ``cone`` the
    unit cone (apex at the origin, axis +z, base radius 1 at z = 1), ``fullscreen`` is one triangle."""
    # icosphere, subdivided once, scaled so that its faces lie outside the unit sphere
    t = (1.0 + 5.0**0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]  # fmt: skip
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]  # fmt: skip
    verts = [np.asarray(p, np.float64) / np.linalg.norm(p) for p in v]
    faces = []
    middle: dict[tuple[int, int], int] = {}

    def mid(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in middle:
            m = verts[a] + verts[b]
            verts.append(m / np.linalg.norm(m))
            middle[key] = len(verts) - 1
        return middle[key]

    for a, b, c in f:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    pos = np.array(verts)
    tri = np.array(faces, np.int64)
    normals = np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    inner = float(np.min(np.abs(np.einsum("ij,ij->i", normals, pos[tri[:, 0]]))))  # nearest face plane
    sphere = (pos / inner).astype(np.float32), tri.astype(np.uint32)
    # cone: apex, base ring (circumscribing the unit circle), base centre
    angles = np.arange(_SEGMENTS) * 2.0 * math.pi / _SEGMENTS
    ring = np.stack([np.cos(angles), np.sin(angles), np.ones(_SEGMENTS)], axis=1) / [
        math.cos(math.pi / _SEGMENTS),
        math.cos(math.pi / _SEGMENTS),
        1.0,
    ]
    cone_pos = np.vstack([[0.0, 0.0, 0.0], ring, [0.0, 0.0, 1.0]]).astype(np.float32)
    sides = [(0, 1 + (k + 1) % _SEGMENTS, 1 + k) for k in range(_SEGMENTS)]
    base = [(_SEGMENTS + 1, 1 + k, 1 + (k + 1) % _SEGMENTS) for k in range(_SEGMENTS)]
    cone = cone_pos, np.array(sides + base, np.uint32)
    triangle = (
        np.array([[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]], np.float32),
        np.array([[0, 1, 2]], np.uint32),
    )
    return {"sphere": sphere, "cone": cone, FULLSCREEN: triangle}


class LightTable:
    """The frame's lights in world space, grouped by (kind, proxy); :meth:`instances` makes eye-space rows.

    ``lights`` are the pre-evaluated (light, world matrix) pairs; ``shadow_faces`` maps id(light) to its
    (first face, face count) in the frame's shadow atlas.  Without any light (ambient lights aside) the
    forward engine's headlight is the one light.
    """

    def __init__(self, lights: list[tuple[Any, np.ndarray]], shadow_faces: dict[int, tuple[int, int]]) -> None:
        from ...attributes import AmbientLight, AreaLight, DirectionalLight, DiscLight, SpotLight

        rows: dict[tuple[str, str], list[np.ndarray]] = {}
        self.count = 0
        self.headlight = not lights
        for light, matrix in lights:
            if isinstance(light, AmbientLight) or not hasattr(light, "diffuse"):
                continue
            row = np.zeros(STRIDE, np.float64)  # world-space data; the view is applied per frame
            row[20:23] = light.diffuse
            row[24:27] = light.specular
            first, faces = shadow_faces.get(id(light), (0, 0))
            row[37:39] = (first, faces)
            if isinstance(light, AreaLight):
                centre, hu, hv, normal = light.world_frame(matrix)
                if float(np.dot(np.cross(hu, hv), normal)) < 0.0:
                    hu = -hu  # HU x HV on the lit side (the shape is symmetric)
                row[16:19], row[19] = centre, 1.0
                row[40:43], row[43] = hu, 1.0 if isinstance(light, DiscLight) else 0.0
                row[44:47], row[47] = hv, 1.0 if light.two_sided else 0.0
                key = ("area", FULLSCREEN)
            elif isinstance(light, DirectionalLight):
                row[16:19] = -light.world_direction(matrix)
                key = ("directional", FULLSCREEN)
            elif hasattr(light, "world_position"):
                reach = light.reach()
                if reach <= 0.0:
                    continue  # too faint to add anything anywhere
                row[16:19] = light.world_position(matrix)
                row[19] = 1.0
                row[23] = reach if math.isfinite(reach) else _FAR
                row[28:31] = (light.constant, light.linear, light.quadratic)
                if isinstance(light, SpotLight):
                    row[32:35] = light.world_direction(matrix)
                    row[35] = light.cos_cutoff
                    row[36] = light.exponent
                    row[39] = math.tan(math.radians(light.cutoff))
                    proxy = "cone" if light.cutoff <= MAX_CONE_CUTOFF else "sphere"
                    key = ("spot", proxy if math.isfinite(reach) else FULLSCREEN)
                else:
                    key = ("point", "sphere" if math.isfinite(reach) else FULLSCREEN)
            else:
                continue
            rows.setdefault(key, []).append(row)
            self.count += 1
        if self.headlight:
            row = np.zeros(STRIDE, np.float64)
            row[20:23] = row[24:27] = 1.0
            row[16:19] = np.nan  # eye space, filled per frame
            rows[("directional", FULLSCREEN)] = [row]
            self.count = 1
        self.groups = {key: np.array(value) for key, value in rows.items()}

    def instances(self, view: np.ndarray) -> list[tuple[str, str, np.ndarray]]:
        """(kind, proxy, float32 instance rows) per group, in the eye space of ``view``."""
        rot = view[:3, :3]
        out = []
        for (kind, proxy), world in self.groups.items():
            data = world.copy()
            n = len(data)
            if kind == "directional":
                if self.headlight:
                    data[:, 16:19] = HEADLIGHT
                else:
                    d = data[:, 16:19] @ rot.T
                    data[:, 16:19] = d / np.linalg.norm(d, axis=1, keepdims=True)
            else:
                data[:, 16:19] = data[:, 16:19] @ rot.T + view[:3, 3]
            proxies = np.zeros((n, 4, 4))
            proxies[:, 3, 3] = 1.0
            reach = data[:, 23]
            if proxy == "sphere":
                for k in range(3):
                    proxies[:, k, k] = reach
                proxies[:, :3, 3] = data[:, 16:19]
            elif proxy == "cone":
                axis = data[:, 32:35] @ rot.T
                axis /= np.linalg.norm(axis, axis=1, keepdims=True)
                helper = np.where(np.abs(axis[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
                u = np.cross(axis, helper)
                u /= np.linalg.norm(u, axis=1, keepdims=True)
                v = np.cross(axis, u)
                width = reach * data[:, 39]
                proxies[:, :3, 0] = u * width[:, None]
                proxies[:, :3, 1] = v * width[:, None]
                proxies[:, :3, 2] = axis * reach[:, None]
                proxies[:, :3, 3] = data[:, 16:19]
            if kind == "area":
                data[:, 40:43] = data[:, 40:43] @ rot.T
                data[:, 44:47] = data[:, 44:47] @ rot.T
            if kind == "spot":
                axis = data[:, 32:35] @ rot.T
                data[:, 32:35] = axis / np.linalg.norm(axis, axis=1, keepdims=True)
            data[:, :16] = proxies.transpose(0, 2, 1).reshape(n, 16)  # column-major for GLSL
            data[:, 39] = 0.0
            out.append((kind, proxy, data.astype(np.float32)))
        return out
