"""Regenerate the demo assets (run once; the output files are committed).

``knot.obj``: a (2,3) trefoil-knot tube, the "mesh loaded from a file" of the demo.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def trefoil_tube(n_around: int = 192, n_tube: int = 14, tube: float = 0.22) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a closed tube around a trefoil knot (about 1.4 units across)."""
    t = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    curve = np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], axis=1) * 0.3
    tangent = np.roll(curve, -1, axis=0) - np.roll(curve, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    ref = np.array([0.0, 0.0, 1.0])
    normal = np.cross(tangent, ref)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangent, normal)
    a = np.linspace(0, 2 * np.pi, n_tube, endpoint=False)
    ring = np.cos(a)[None, :, None] * normal[:, None, :] + np.sin(a)[None, :, None] * binormal[:, None, :]
    vertices = (curve[:, None, :] + tube * ring).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_around), np.arange(n_tube), indexing="ij")
    i2, j2 = (i + 1) % n_around, (j + 1) % n_tube
    v00, v10, v01, v11 = i * n_tube + j, i2 * n_tube + j, i * n_tube + j2, i2 * n_tube + j2
    faces = np.concatenate([np.stack([v00, v10, v11], -1).reshape(-1, 3), np.stack([v00, v11, v01], -1).reshape(-1, 3)])
    return vertices, faces


def main() -> None:
    import trimesh

    here = Path(__file__).parent
    v, f = trefoil_tube()
    mesh = trimesh.Trimesh(v, f, process=False)
    if mesh.volume < 0:
        mesh.invert()
    mesh.export(here / "knot.obj", digits=5)
    print(f"knot.obj: {len(v)} vertices, {len(f)} triangles, watertight={mesh.is_watertight}")


if __name__ == "__main__":
    main()
