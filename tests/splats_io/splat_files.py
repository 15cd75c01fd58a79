"""Small splat clouds and hand-written trainer ``.ply`` files for the splat file tests (generated, no downloads)."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

import omnirender as om


def cloud_arrays(n: int = 20, degree: int = 0, seed: int = 5) -> dict[str, np.ndarray]:
    """float32 arrays of ``om.GaussianSplats`` (unit quaternions, linear scales, opacities in (0, 1))."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return {
        "positions": (rng.normal(size=(n, 3)) * 0.5).astype(np.float32),
        "rotations": q.astype(np.float32),
        "scales": (np.exp(rng.normal(size=(n, 3)) * 0.3) * 0.1).astype(np.float32),
        "opacities": rng.uniform(0.2, 0.95, n).astype(np.float32),
        "sh": rng.normal(scale=0.4, size=(n, (degree + 1) ** 2, 3)).astype(np.float32),
    }


def trainer_ply(path: Path, rows: list[list[float]], names: list[str], fmt: str = "binary_little_endian") -> Path:
    """A PLY file with one float ``vertex`` property per name and the given rows (as the trainer writes it)."""
    head = f"ply\nformat {fmt} 1.0\nelement vertex {len(rows)}\n"
    head += "".join(f"property float {n}\n" for n in names) + "end_header\n"
    if fmt == "ascii":
        body = "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows).encode()
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        body = b"".join(struct.pack(order + "f" * len(names), *row) for row in rows)
    path.write_bytes(head.encode() + body)
    return path


def degree1_names() -> list[str]:
    return (
        ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
        + [f"f_rest_{i}" for i in range(9)]
        + ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    )


def find_splats(node: om.Node) -> list[om.GaussianSplats]:
    out = [c for c in node.components if isinstance(c, om.GaussianSplats)]
    for child in node.children:
        out += find_splats(child)
    return out
