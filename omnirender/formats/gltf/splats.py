"""``om.GaussianSplats`` in glTF: the ``KHR_gaussian_splatting`` extension (written and read).

The extension stores splats on a ``POINTS`` primitive whose
``extensions.KHR_gaussian_splatting`` object names the ``"ellipse"`` kernel and
the colour space:

=================================================  ==========================================================
``POSITION``                                        centres (local space; the node's transform applies)
``KHR_gaussian_splatting:ROTATION``                 unit quaternions in glTF's **(x, y, z, w)** order
                                                    (omnirender holds (w, x, y, z): reordered both ways)
``KHR_gaussian_splatting:SCALE``                    linear standard deviations
``KHR_gaussian_splatting:OPACITY``                  opacities in [0, 1] (not logits)
``KHR_gaussian_splatting:SH_DEGREE_l_COEF_n``       spherical-harmonics coefficients, ``sh[:, l*l + n]``
``COLOR_0``                                         the fallback point colour: ``0.5 + C0 * sh[:, 0]``
                                                    clamped, made linear (glTF vertex colours are linear),
                                                    opacity in alpha
=================================================  ==========================================================

omnirender's splat colours are the reference trainer's: display-referred
sRGB values, so the writer declares ``"colorSpace": "srgb_rec709_display"``;
the reader accepts that and ``"lin_rec709_display"`` (whose colours it
converts: the SH evaluation is linear in the coefficients, so the DC term is
re-encoded and the higher terms kept, exact for view-independent splats and a
documented approximation otherwise) and refuses other kernels and colour
spaces with an error naming them.  Extension-defined integer encodings
(normalised bytes and shorts) are read through the accessor's ``normalized``
flag.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...core import ShapePainter, default_for
from ...geometry.trs import decomposable
from ...shapes import GaussianSplats
from ..colors import srgb_to_linear
from .glb import ARRAY_BUFFER
from .writer import GLTFEngine

__all__ = ["EXTENSION", "GaussianSplatsExporter", "read_splats", "COLOR_SPACE"]

EXTENSION = "KHR_gaussian_splatting"
#: The colour space omnirender's splat colours are in (see the module docs).
COLOR_SPACE = "srgb_rec709_display"
_PREFIX = EXTENSION + ":"
_C0 = 0.28209479177387814
_POINTS = 0


def _semantic(k: int) -> str:
    degree = int(np.floor(np.sqrt(k)))
    return f"{_PREFIX}SH_DEGREE_{degree}_COEF_{k - degree * degree}"


def _baked(splats: GaussianSplats, matrix: np.ndarray) -> dict[str, np.ndarray]:
    """The splats with an affine ``matrix`` a glTF node cannot hold (shear) applied to centres and covariances."""
    a = np.asarray(matrix, np.float64)[:3, :3]
    p = np.asarray(splats.positions, np.float64)
    r = splats.rotation_matrices() * np.asarray(splats.scales, np.float64)[:, None, :]
    cov = a @ r @ np.swapaxes(r, 1, 2) @ a.T
    values, vectors = np.linalg.eigh(cov)
    vectors[np.linalg.det(vectors) < 0, :, 0] *= -1.0  # proper rotations
    from scipy.spatial.transform import Rotation as SciRotation

    xyzw = SciRotation.from_matrix(vectors).as_quat()
    return {
        "positions": p @ a.T + np.asarray(matrix, np.float64)[:3, 3],
        "rotations_xyzw": xyzw,
        "scales": np.sqrt(np.maximum(values, 1e-30)),
    }


@default_for(GLTFEngine)
class GaussianSplatsExporter(ShapePainter):
    """``GaussianSplats`` -> a ``POINTS`` primitive with ``KHR_gaussian_splatting`` (see the module docs)."""

    __slots__ = ()
    service = GLTFEngine.service
    target = GaussianSplats

    def exec(self, shape: GaussianSplats, engine: Any) -> None:
        n = shape.count
        if n == 0:
            return
        if engine._capture is not None:  # inside an instance set's shape
            engine._capture.fail("its shape holds Gaussian splats, which EXT_mesh_gpu_instancing cannot instance")
            return
        g = engine.gltf
        local = engine.local_matrix()
        if decomposable(local):
            p = np.asarray(shape.positions, np.float64)
            q = np.asarray(shape.rotations, np.float64)[:, [1, 2, 3, 0]]  # (w, x, y, z) -> glTF's (x, y, z, w)
            s = np.asarray(shape.scales, np.float64)
        else:
            baked = _baked(shape, local)
            p, q, s = baked["positions"], baked["rotations_xyzw"], baked["scales"]
        sh = np.asarray(shape.sh, np.float32)
        opacity = np.asarray(shape.opacities, np.float32).reshape(n)
        dc = np.clip(0.5 + _C0 * sh[:, 0, :].astype(np.float64), 0.0, 1.0)
        colour = np.concatenate([srgb_to_linear(dc), opacity[:, None]], axis=1).astype(np.float32)
        attrs = {
            "POSITION": g.accessor(p.astype(np.float32), ARRAY_BUFFER, bounds=True),
            "COLOR_0": g.accessor(colour, ARRAY_BUFFER),
            _PREFIX + "ROTATION": g.accessor(q.astype(np.float32), ARRAY_BUFFER),
            _PREFIX + "SCALE": g.accessor(s.astype(np.float32), ARRAY_BUFFER),
            _PREFIX + "OPACITY": g.accessor(opacity, ARRAY_BUFFER),
        }
        for k in range(sh.shape[1]):
            attrs[_semantic(k)] = g.accessor(np.ascontiguousarray(sh[:, k, :]), ARRAY_BUFFER)
        primitive = {
            "attributes": attrs,
            "mode": _POINTS,
            "extensions": {
                EXTENSION: {
                    "kernel": "ellipse",
                    "colorSpace": COLOR_SPACE,
                    "projection": "perspective",
                    "sortingMethod": "cameraDistance",
                }
            },
        }
        g.use_extension(EXTENSION)
        mesh = g.append("meshes", {"name": "GaussianSplats", "primitives": [primitive]})
        if decomposable(local):
            engine.mesh_node("GaussianSplats", mesh)
        else:  # the matrix is baked into the splats: the node sits at the enclosing node's frame
            index = g.append("nodes", {"name": "GaussianSplats", "mesh": mesh})
            engine._attach(index)


def read_splats(read: Any, attrs: dict[str, Any], spec: Any, error: Any) -> GaussianSplats:
    """The ``om.GaussianSplats`` of a ``KHR_gaussian_splatting`` primitive.

    ``read(semantic)`` returns an attribute's accessor as an array; ``spec``
    is the primitive's extension object; ``error(message)`` makes the
    reader's exception (naming the file and primitive).
    """
    if not isinstance(spec, dict):
        raise error(f"the {EXTENSION} extension object must be an object, got {type(spec).__name__}")
    kernel = spec.get("kernel")
    if kernel != "ellipse":
        raise error(f"{EXTENSION} kernel {kernel!r} is not supported (omnirender renders the 'ellipse' kernel)")
    space = spec.get("colorSpace")
    if space not in ("srgb_rec709_display", "lin_rec709_display"):
        raise error(
            f"{EXTENSION} colorSpace {space!r} is not supported (supported: srgb_rec709_display, lin_rec709_display)"
        )
    for name in ("POSITION", _PREFIX + "ROTATION", _PREFIX + "SCALE", _PREFIX + "OPACITY", _semantic(0)):
        if name not in attrs:
            raise error(f"a {EXTENSION} primitive needs the attribute {name}")
    positions = np.asarray(read("POSITION"), np.float32)
    n = len(positions)

    def attribute(name: str, width: int) -> np.ndarray:
        a = np.asarray(read(name), np.float64)
        a = a.reshape(len(a), -1)
        if a.shape != (n, width):
            raise error(f"{name} holds {a.shape[0]} x {a.shape[1]} values; {n} x {width} expected (one per splat)")
        return a

    xyzw = attribute(_PREFIX + "ROTATION", 4)
    length = np.linalg.norm(xyzw, axis=1)
    if n and not (length > 1e-12).all():
        raise error(f"{_PREFIX}ROTATION of splat {int(np.argmin(length > 1e-12))} is the zero quaternion")
    rotations = (xyzw[:, [3, 0, 1, 2]] / np.maximum(length, 1e-300)[:, None]).astype(np.float32)
    scales = attribute(_PREFIX + "SCALE", 3).astype(np.float32)
    opacities = attribute(_PREFIX + "OPACITY", 1).reshape(n).astype(np.float32)
    degree = 0
    while degree < 3 and any(_semantic(k) in attrs for k in range((degree + 1) ** 2, (degree + 2) ** 2)):
        degree += 1
    count = (degree + 1) ** 2
    missing = [_semantic(k) for k in range(count) if _semantic(k) not in attrs]
    if missing:
        raise error(f"spherical harmonics of degree {degree} are partly defined: {', '.join(missing)} missing")
    sh = np.stack([attribute(_semantic(k), 3) for k in range(count)], axis=1)
    if space == "lin_rec709_display":  # re-encode the DC colour as the display value omnirender's colours are
        from ...attributes.photometry import linear_to_srgb

        base = np.clip(0.5 + _C0 * sh[:, 0, :], 0.0, 1.0)
        sh[:, 0, :] = (linear_to_srgb(base) - 0.5) / _C0
    try:
        return GaussianSplats(positions, rotations, scales, opacities, sh.astype(np.float32))
    except ValueError as exc:
        raise error(str(exc)) from None
