"""``om.load_usd``: an OpenUSD stage (read and composed by ``usd-core``) as a scene graph.

The prim hierarchy becomes nodes with the prims' names, so the USD path
``/World/Robot/Arm`` is the node path ``/<root>/World/Robot/Arm`` (``root["/World/Robot/Arm"]``).
What each prim becomes:

- ``Xformable``: its composed local matrix (``resetXformStack`` honoured) as
  an ``om.Matrix``; time-sampled transforms as ``Translation``/``Rotation``/
  ``Scaling`` keyframe tracks of an ``om.Animation`` on the root (times in
  seconds from ``startTimeCode``); invisible prims and prims whose purpose is
  not in ``purposes`` are not loaded; ``kind`` becomes the group ``kind:<kind>``;
- ``Mesh``: n-gons fan-triangulated with numpy, normals, ``st``,
  ``displayColor``/``displayOpacity`` of any interpolation (constant, uniform,
  vertex, varying, faceVarying, indexed or not), ``leftHanded`` orientation,
  GeomSubsets (``materialBind`` family) with their own materials; Catmull-Clark
  and Loop meshes are drawn as their control cage (one warning per stage);
- ``Sphere``, ``Cube``, ``Cylinder``, ``Cone`` (with ``axis``) as the omnirender
  shapes, ``Capsule`` as a cylinder with two spheres; ``Points`` as a
  ``PointSet``; ``BasisCurves`` as a ``LineSet`` through their vertices;
- ``UsdPreviewSurface`` materials (``UsdUVTexture``, ``UsdPrimvarReader``,
  ``UsdTransform2d``) as ``om.PBRMaterial`` with texture slots
  (:mod:`.materials`); other networks fall back with a warning naming them;
- ``UsdLux`` lights and ``UsdGeomCamera`` (:mod:`.lights`);
- ``PointInstancer``: one ``om.InstanceSet`` per prototype shape;
  instanceable prims share one node per prototype (one upload).

Colours in USD are linear; omnirender's are display (sRGB) values, so they are
converted.  Files referenced by the stage (layers, textures) must lie inside
the stage's folder unless ``trusted=True`` (:func:`check_layers`).
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ...animation.animation import Animation
from ...animation.tracks import Keyframes
from ...attributes import Color, Material, PBRMaterial, Texture
from ...attributes.photometry import linear_to_srgb
from ...core.paths import PathPolicy
from ...core.transform import Matrix, Rotation, Scaling, Translation
from ...geometry.trs import decompose_trs
from ...scene.node import Node
from ...shapes import Box, Cone, Cylinder, InstanceSet, LineSet, PointSet, Sphere, TriangleSet
from .materials import MaterialReader
from .policy import check_layers

__all__ = ["load_usd", "USDImportError", "flatten_usd"]


class USDImportError(ValueError):
    """A USD stage that cannot be read (the message names the file and prim)."""


def _pxr() -> Any:
    try:
        from pxr import Usd
    except ImportError as exc:  # pragma: no cover - usd-core is the 'usd' extra
        raise ImportError(f"load_usd needs usd-core (pip install omnirender[usd]): {exc}") from None
    return Usd


def load_usd(
    source: Any,
    *,
    camera: str | None = None,
    purposes: tuple[str, ...] = ("default", "render"),
    animation: bool = True,
    trusted: bool = False,
) -> Node:
    """The stage ``source`` (a path to ``.usd``/``.usda``/``.usdc``/``.usdz`` or a ``pxr.Usd.Stage``) as a Node.

    ``camera``: the USD path of the camera to use (default: every camera, the
    first one met in the hierarchy is the scene's).  ``purposes``: the prim
    purposes loaded (``"proxy"`` and ``"guide"`` prims are left out by default).
    ``animation``: time-sampled transforms become an ``om.Animation``.
    ``trusted``: allow layers and textures outside the stage's folder.
    """
    Usd = _pxr()
    if isinstance(source, Usd.Stage):
        stage = source
        layer_path = stage.GetRootLayer().realPath
        name = Path(layer_path).stem if layer_path else "stage"
        folder = Path(layer_path).parent if layer_path else None
    else:
        if not isinstance(source, (str, os.PathLike)):
            raise TypeError(f"load_usd: source must be a path or a pxr.Usd.Stage, got {type(source).__name__}")
        path = Path(os.fspath(source))
        if not path.is_file():
            raise FileNotFoundError(f"load_usd: no such file {str(path)!r}")
        try:
            stage = Usd.Stage.Open(str(path))
        except Exception as exc:  # pxr raises Tf.ErrorException
            raise USDImportError(f"load_usd {str(path)!r}: cannot open the stage: {_first_line(exc)}") from None
        if stage is None:
            raise USDImportError(f"load_usd {str(path)!r}: not a USD stage")
        name, folder = path.stem, path.resolve().parent
    check_layers(stage, folder, trusted)
    errors = [str(e) for e in stage.GetCompositionErrors()] if hasattr(stage, "GetCompositionErrors") else []
    if errors:  # USD composed what it could; say what it could not
        more = f" (and {len(errors) - 5} more)" if len(errors) > 5 else ""
        warnings.warn(f"load_usd {name}: composition errors: {'; '.join(errors[:5])}{more}", stacklevel=2)
    return _StageReader(stage, name, folder, trusted, purposes, camera, animation).build()


def flatten_usd(path: str | os.PathLike[str], *, trusted: bool = False) -> list[tuple[list[Any], TriangleSet]]:
    """The triangle sets of a stage in world coordinates with their attributes: what ``om.MeshFile`` reads."""
    from ...core import SIMPLIFY, Engine, Shape
    from ...core.transform import Transform

    root = load_usd(path, animation=False, trusted=trusted)
    out: list[tuple[list[Any], Any]] = []
    engine = Engine()  # its simplifiers turn spheres, boxes... into triangle sets

    def walk(items: list[Any], matrix: np.ndarray, attrs: list[Any]) -> None:
        attrs = list(attrs)
        for item in items:
            if isinstance(item, Transform):
                matrix = matrix @ item.matrix
            elif isinstance(item, Node):
                walk(list(item.items), matrix, attrs)
            elif isinstance(item, TriangleSet):
                out.append((list(attrs), item.transformed(matrix)))
            elif isinstance(item, (PBRMaterial, Material, Color, Texture)):
                attrs.append(item)
            elif isinstance(item, Shape) and not isinstance(item, (LineSet, PointSet, InstanceSet)):
                simplifier = engine.find_handler(SIMPLIFY, type(item))
                if simplifier is not None:
                    walk(list(simplifier.exec(item, engine)), matrix, attrs)

    walk([root], np.eye(4), [])
    return out


def mesh_parts(
    path: str, *, policy: PathPolicy | None = None, strict: bool = False
) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """``om.MeshFile`` parts of a USD file (registered by :mod:`omnirender.formats`).

    ``policy.trusted`` is passed on (the stage's own check of its layers and
    textures, :mod:`.policy`); ``allowed_roots`` and ``strict`` are not used yet.
    """
    try:
        flat = flatten_usd(path, trusted=bool(policy and policy.trusted))
    except USDImportError as exc:
        raise ValueError(f"MeshFile: {exc}") from None
    parts = [({"kind": "attributes", "attributes": attrs} if attrs else None, ts) for attrs, ts in flat]
    if not parts:
        raise ValueError(f"MeshFile: {path!r} contains no meshes")
    return parts


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[-1].strip() if text else type(exc).__name__


def _gf(m: Any) -> np.ndarray:
    """A Gf.Matrix4d (row vectors) as omnirender's column-vector matrix."""
    return np.array(m, dtype=np.float64).reshape(4, 4).T


def _srgb(rgb: Any) -> np.ndarray:
    return np.clip(linear_to_srgb(np.clip(np.asarray(rgb, np.float64), 0.0, None)), 0.0, 1.0)


#: omnirender's shapes stand on the y axis: the rotation taking y to a USD ``axis``.
_AXIS = {
    "Y": None,
    "Z": np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], np.float64),
    "X": np.array([[0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], np.float64),
}


class _StageReader:
    def __init__(
        self,
        stage: Any,
        name: str,
        folder: Path | None,
        trusted: bool,
        purposes: tuple[str, ...],
        camera: str | None,
        animate: bool,
    ) -> None:
        from pxr import Usd, UsdGeom

        self.Usd, self.UsdGeom = Usd, UsdGeom
        self.stage = stage
        self.name = name
        self.purposes = set(purposes)
        self.camera_path = camera
        self.animate = animate
        self.time = Usd.TimeCode.EarliestTime()
        self.tps = float(stage.GetTimeCodesPerSecond() or 24.0)
        self.start = float(stage.GetStartTimeCode()) if stage.HasAuthoredTimeCodeRange() else 0.0
        self.end = float(stage.GetEndTimeCode()) if stage.HasAuthoredTimeCodeRange() else self.start
        self.materials = MaterialReader(stage, name, folder, trusted)
        self.tracks: list[Any] = []
        self.prototypes: dict[str, Node] = {}
        self.subdivided: list[str] = []
        self.cameras = 0
        self.uv_names: list[str] = ["st"]
        self.frozen: list[str] = []  # time-varying attributes read at one time (only transforms are animated)

    def warn(self, message: str) -> None:
        warnings.warn(f"load_usd {self.name}: {message}", stacklevel=4)

    # -- hierarchy ---------------------------------------------------------------------
    def build(self) -> Node:
        root = Node(_node_name(self.name))
        if self.UsdGeom.GetStageUpAxis(self.stage) == "Z":  # omnirender scenes are y-up
            root.add(Matrix(np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]], np.float64)))
        pseudo = self.stage.GetPseudoRoot()
        for child in pseudo.GetChildren():
            node = self.prim(child, np.eye(4))
            if node is not None:
                root.add(node)
        if self.subdivided:
            shown = ", ".join(self.subdivided[:5]) + (" ..." if len(self.subdivided) > 5 else "")
            self.warn(
                f"{len(self.subdivided)} subdivision surface(s) drawn as their control cage ({shown}); "
                "author subdivisionScheme = 'none' for polygon meshes"
            )
        if self.frozen:
            shown = ", ".join(self.frozen[:5]) + (" ..." if len(self.frozen) > 5 else "")
            self.warn(
                f"{len(self.frozen)} time-sampled attribute(s) other than transforms are read at the start time "
                f"only ({shown})"
            )
        if self.camera_path is not None and self.cameras == 0:
            raise USDImportError(f"load_usd {self.name}: no camera at {self.camera_path!r}")
        background = self.stage.GetDefaultPrim()
        if background and background.GetAttribute("omnirender:background"):
            value = background.GetAttribute("omnirender:background").Get()
            if value is not None:
                from ...attributes import Background

                root.insert(0, Background(tuple(value)[:3]))
        if self.tracks:
            duration = max((self.end - self.start) / self.tps, max(float(t.times[-1]) for t in self.tracks))
            root.add(Animation(self.tracks, duration=duration if duration > 0 else None, fps=self.tps))
        return root

    def prim(self, prim: Any, parent_world: np.ndarray) -> Node | None:
        UsdGeom = self.UsdGeom
        if not prim.IsActive() or not prim.IsDefined() or prim.IsAbstract():
            return None
        type_name = str(prim.GetTypeName())
        if type_name in ("Material", "Shader", "NodeGraph", "GeomSubset"):
            return None
        imageable = UsdGeom.Imageable(prim)
        if imageable:
            if self.animate and imageable.GetVisibilityAttr().ValueMightBeTimeVarying():
                self.frozen.append(str(imageable.GetVisibilityAttr().GetPath()))
            if imageable.GetVisibilityAttr().Get(self.time) == UsdGeom.Tokens.invisible:
                return None
            purpose = imageable.GetPurposeAttr().Get()
            if purpose and str(purpose) not in self.purposes:
                return None
        kind = self.Usd.ModelAPI(prim).GetKind()
        groups = [f"kind:{kind}"] if kind else []
        groups += [str(g) for g in prim.GetCustomDataByKey("omnirender:groups") or ()]
        name = prim.GetCustomDataByKey("omnirender:name") or prim.GetName()
        node = Node(_node_name(name), groups=groups)
        world = parent_world
        if prim.IsA(UsdGeom.Xformable):
            world = self.xform(prim, node, parent_world)
        self.content(prim, type_name, node)
        if prim.IsInstance():
            node.add(self.prototype(prim.GetPrototype(), world))
        elif not prim.IsA(UsdGeom.PointInstancer):  # an instancer's prototypes are drawn by the instancer
            for child in prim.GetChildren():
                built = self.prim(child, world)
                if built is not None:
                    node.add(built)
        return node

    def prototype(self, proto: Any, world: np.ndarray) -> Node:
        """The one node every instance of an instanceable prim shares (uploaded once)."""
        key = str(proto.GetPath())
        if key not in self.prototypes:
            shared = Node("prototype")
            for child in proto.GetChildren():
                built = self.prim(child, world)
                if built is not None:
                    shared.add(built)
            self.prototypes[key] = shared
        return self.prototypes[key]

    def xform(self, prim: Any, node: Node, parent_world: np.ndarray) -> np.ndarray:
        xf = self.UsdGeom.Xformable(prim)
        reset = xf.GetResetXformStack()
        local = _gf(xf.GetLocalTransformation(self.time))
        if reset:  # the prim's own matrix is its world matrix
            inverse = np.linalg.inv(parent_world) if abs(np.linalg.det(parent_world)) > 1e-300 else np.eye(4)
            fix = inverse
        else:
            fix = np.eye(4)
        samples = xf.GetTimeSamples() if self.animate and xf.TransformMightBeTimeVarying() else []
        if len(samples) > 1:
            self.animated(xf, node, samples, fix, prim)
        elif not np.allclose(fix @ local, np.eye(4), atol=0.0, rtol=0.0):
            node.add(_matrix(fix @ local, prim))
        return parent_world @ fix @ local

    def animated(self, xf: Any, node: Node, samples: list[float], fix: np.ndarray, prim: Any) -> None:
        matrices = np.stack([fix @ _gf(xf.GetLocalTransformation(self.Usd.TimeCode(t))) for t in samples])
        trs = decompose_trs(matrices)
        if not trs.valid.all():
            bad = str(trs.reason[~trs.valid][0])
            self.warn(f"{prim.GetPath()}: an animated transform is {bad}; its first sample is used")
            node.add(_matrix(matrices[0], prim))
            return
        times = (np.asarray(samples, np.float64) - self.start) / self.tps
        quats = trs.rotation[:, [3, 0, 1, 2]]  # (x, y, z, w) -> (w, x, y, z)
        quats[1:] *= np.where(np.sum(quats[1:] * quats[:-1], axis=1) < 0.0, -1.0, 1.0)[:, None]  # shortest arcs
        translation = node.add(Translation(trs.translation[0]))
        rotation = node.add(Rotation.from_quaternion(*quats[0]))
        scaling = node.add(Scaling(trs.scale[0]))
        self.tracks += [
            Keyframes(translation, "offset", times, trs.translation),
            Keyframes(rotation, "quaternion", times, quats),
            Keyframes(scaling, "factors", times, trs.scale),
        ]

    # -- prims -------------------------------------------------------------------------
    def content(self, prim: Any, type_name: str, node: Node) -> None:
        UsdGeom = self.UsdGeom
        from . import lights

        if prim.IsA(UsdGeom.Camera):
            if self.camera_path is None or str(prim.GetPath()) == self.camera_path:
                node.add(lights.camera(UsdGeom.Camera(prim), self.time))
                self.cameras += 1
            return
        light = lights.light(prim, self.time, self.materials, self.warn)
        if light is not False:
            if light is not None:
                node.add(light)
            return
        if prim.IsA(UsdGeom.PointInstancer):
            for child in self.instancer(UsdGeom.PointInstancer(prim)):
                node.add(child)
            return
        if type_name == "ParticleField3DGaussianSplat":
            from .splats import read_splats

            splats = read_splats(prim, self.time, self.warn)
            if splats is not None:
                node.add(splats)
            return
        if prim.IsA(UsdGeom.Gprim):
            for child in self.gprim(prim, type_name):
                if isinstance(child, Node):
                    node.add(child)
                else:
                    node.add(child)

    def gprim(self, prim: Any, type_name: str) -> list[Any]:
        """The components of a gprim: its material then its shape(s), or child nodes (mesh subsets)."""
        UsdGeom = self.UsdGeom
        gprim = UsdGeom.Gprim(prim)
        if prim.IsA(UsdGeom.Mesh):
            return self.mesh(UsdGeom.Mesh(prim))
        display = self.display(gprim)
        material = self.materials.bound(prim, display_color=display)
        shape: Any
        if prim.IsA(UsdGeom.Sphere):
            shape = Sphere(radius=float(UsdGeom.Sphere(prim).GetRadiusAttr().Get(self.time)))
            return [*material, shape]
        if prim.IsA(UsdGeom.Cube):
            return [*material, Box(size=float(UsdGeom.Cube(prim).GetSizeAttr().Get(self.time)))]
        if type_name in ("Cylinder", "Cone", "Capsule"):
            schema = getattr(UsdGeom, type_name)(prim)
            radius = float(schema.GetRadiusAttr().Get(self.time))
            height = float(schema.GetHeightAttr().Get(self.time))
            axis = _AXIS.get(str(schema.GetAxisAttr().Get(self.time)), None)
            items: list[Any] = [Matrix(axis)] if axis is not None else []
            if type_name == "Cylinder":
                items.append(Cylinder(radius=radius, height=height))
            elif type_name == "Cone":
                items.append(Cone(radius=radius, height=height))
            else:  # a capsule: the cylinder's caps are hidden inside the two spheres
                items += [Cylinder(radius=radius, height=height)] if height > 0 else []
                items += [
                    Node("top", [Translation(0.0, height / 2, 0.0), Sphere(radius=radius)]),
                    Node("bottom", [Translation(0.0, -height / 2, 0.0), Sphere(radius=radius)]),
                ]
            return (
                [*material, Node(type_name.lower(), items)]
                if axis is not None or type_name == "Capsule"
                else [
                    *material,
                    *items,
                ]
            )
        if prim.IsA(UsdGeom.Points):
            return self.points(UsdGeom.Points(prim), material)
        if prim.IsA(UsdGeom.BasisCurves):
            return self.curves(UsdGeom.BasisCurves(prim), material)
        self.warn(f"{prim.GetPath()}: {type_name} prims are not supported; left out")
        return []

    def display(self, gprim: Any) -> tuple[np.ndarray | None, float | None]:
        """The constant displayColor (linear RGB) and displayOpacity of a gprim, or None where not constant."""
        color = opacity = None
        pv = gprim.GetDisplayColorPrimvar()
        if pv and pv.HasAuthoredValue():
            values = np.asarray(pv.ComputeFlattened(self.time) or [], np.float64).reshape(-1, 3)
            if len(values) >= 1 and (pv.GetInterpolation() == "constant" or np.ptp(values, axis=0).max() == 0.0):
                color = values[0]
        pv = gprim.GetDisplayOpacityPrimvar()
        if pv and pv.HasAuthoredValue():
            values = np.asarray(pv.ComputeFlattened(self.time) or [], np.float64).reshape(-1)
            if len(values) >= 1 and (pv.GetInterpolation() == "constant" or np.ptp(values) == 0.0):
                opacity = float(values[0])
        return color, opacity

    # -- meshes ------------------------------------------------------------------------
    def mesh(self, mesh: Any) -> list[Any]:
        prim = mesh.GetPrim()
        where = str(prim.GetPath())
        if self.animate and mesh.GetPointsAttr().ValueMightBeTimeVarying():
            self.frozen.append(str(mesh.GetPointsAttr().GetPath()))
        points = np.asarray(mesh.GetPointsAttr().Get(self.time) or [], np.float32).reshape(-1, 3)
        counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get(self.time) or [], np.int32)
        fvi = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(self.time) or [], np.int32)
        if len(points) == 0 or len(counts) == 0:
            return []
        if counts.sum(dtype=np.int64) != len(fvi) or counts.min() < 0:
            raise USDImportError(f"load_usd {self.name}: {where}: faceVertexCounts do not add up to the indices")
        if len(fvi) and (fvi.min() < 0 or fvi.max() >= len(points)):
            raise USDImportError(f"load_usd {self.name}: {where}: a face vertex index is out of range")
        scheme = str(mesh.GetSubdivisionSchemeAttr().Get())
        if scheme not in ("none", "bilinear"):
            self.subdivided.append(where)
        left = str(mesh.GetOrientationAttr().Get()) == "leftHanded"
        k = int(counts[0])
        cached: dict[str, np.ndarray] = {}

        def fan() -> tuple[np.ndarray, np.ndarray]:
            """(T, 3) face-vertex corners and (T,) face of each triangle (computed when needed)."""
            if "corners" not in cached:
                corners, cached["faces"] = triangulate(counts)
                cached["corners"] = corners[:, [0, 2, 1]] if left else corners
            return cached["corners"], cached["faces"]

        if k in (3, 4) and counts.min() == counts.max():  # one gather from the (F, k) index table
            order = [0, 1, 2] if k == 3 else [0, 1, 2, 0, 2, 3]
            if left:
                order = [0, 2, 1] if k == 3 else [0, 2, 1, 0, 3, 2]
            tri_points = fvi.reshape(-1, k)[:, order].reshape(-1, 3)
        else:
            tri_points = fvi[fan()[0]]  # (T, 3) point indices
        self.uv_names = self.materials.uv_names(prim)
        primvars = self.mesh_primvars(mesh, counts, fvi, len(points))
        display = self.display(mesh)
        per_corner = any(interp in ("faceVarying", "uniform") for interp, _ in primvars.values())
        if per_corner:  # unweld: one vertex per triangle corner
            corners, faces = fan()
            flat_corners = corners.reshape(-1)
            vertices = points[tri_points.reshape(-1)]
            indices = np.arange(len(vertices), dtype=np.int64).reshape(-1, 3)
            tri_face = np.repeat(faces, 3)

            def spread(interp: str, values: np.ndarray) -> np.ndarray:
                if interp == "faceVarying":
                    return values[flat_corners]
                if interp == "uniform":
                    return values[tri_face]
                if interp in ("vertex", "varying"):
                    return values[fvi[flat_corners]]
                return np.broadcast_to(values[0], (len(vertices), values.shape[1]))

        else:
            mask = np.zeros(len(points), bool)
            mask[tri_points.reshape(-1)] = True
            if not mask.all():  # points no face uses would only inflate the bounds
                used = np.flatnonzero(mask)
                remap = np.cumsum(mask) - 1
                vertices, indices = points[used], remap[tri_points]
            else:
                used, vertices, indices = None, points, tri_points

            def spread(interp: str, values: np.ndarray) -> np.ndarray:
                if interp in ("vertex", "varying"):
                    return values if used is None else values[used]
                return np.broadcast_to(values[0], (len(vertices), values.shape[1]))

        arrays: dict[str, Any] = {}
        if "normals" in primvars:
            interp, values = primvars["normals"]
            n = spread(interp, values).astype(np.float32)
            if str(mesh.GetOrientationAttr().Get()) == "leftHanded":
                n = -n
            if len(n) and np.einsum("ij,ij->i", n, n).min() < 1e-24:  # TriangleSet refuses zero-length normals
                self.warn(f"{where}: some normals have zero length; smooth normals are computed instead")
            else:
                arrays["normals"] = n  # normalised by TriangleSet
        for uv_name in self.uv_names:
            if uv_name in primvars:
                interp, values = primvars[uv_name]
                arrays["texcoords"] = spread(interp, values).astype(np.float32)
                break
        colored = "displayColor" in primvars and display[0] is None and self.materials.uses_display_color(prim)
        if colored:
            interp, values = primvars["displayColor"]
            rgb = _srgb(spread(interp, values))
            if "displayOpacity" in primvars and display[1] is None:
                interp, values = primvars["displayOpacity"]
                rgb = np.concatenate([rgb, spread(interp, values)[:, :1]], axis=1)
            arrays["colors"] = rgb.astype(np.float32)
        vertices = np.ascontiguousarray(vertices)
        triangles: list[tuple[Any, np.ndarray]] = []  # (material prim or None, triangle rows)
        subsets = self.UsdGeom.Subset.GetGeomSubsets(mesh, "face", "materialBind")
        if subsets:
            faces = fan()[1]
            taken = np.zeros(len(counts), bool)
            for subset in subsets:
                ids = np.asarray(subset.GetIndicesAttr().Get(self.time) or [], np.int64)
                ids = ids[(ids >= 0) & (ids < len(counts))]
                mask = np.zeros(len(counts), bool)
                mask[ids] = True
                mask &= ~taken
                taken |= mask
                triangles.append((subset.GetPrim(), np.flatnonzero(mask[faces])))
            rest = np.flatnonzero(~taken[faces])
            if len(rest):
                triangles.append((None, rest))
        else:
            triangles.append((None, None))
        out: list[Any] = []
        for part, rows in triangles:
            if rows is not None and len(rows) == 0:
                continue
            tri = indices if rows is None else indices[rows]
            try:
                shape = TriangleSet(vertices, tri, **arrays)
            except ValueError as exc:
                raise USDImportError(f"load_usd {self.name}: {where}: {exc}") from None
            material = self.materials.bound(
                prim if part is None else part, display_color=display, vertex_colors=colored, fallback=prim
            )
            if part is None:
                out += [*material, shape]
            else:
                out.append(Node(_node_name(part.GetName()), [*material, shape]))
        if not mesh.GetDoubleSidedAttr().Get():
            pass  # single-sided meshes draw both sides here, as PBRMaterial's default (documented)
        return out

    def mesh_primvars(
        self, mesh: Any, counts: np.ndarray, fvi: np.ndarray, n_points: int
    ) -> dict[str, tuple[str, np.ndarray]]:
        """name -> (interpolation, flattened values (K, C)) of the primvars omnirender draws."""
        api = self.UsdGeom.PrimvarsAPI(mesh.GetPrim())
        wanted = {"displayColor": 3, "displayOpacity": 1}
        for uv_name in self.uv_names:
            wanted[uv_name] = 2
        sizes = {"constant": 1, "uniform": len(counts), "faceVarying": len(fvi)}
        out: dict[str, tuple[str, np.ndarray]] = {}

        def accept(name: str, interp: str, values: np.ndarray) -> None:
            expected = sizes.get(interp, n_points)
            if len(values) < expected:
                self.warn(f"{mesh.GetPath()}: primvar {name} has {len(values)} values, {interp} needs {expected}")
                return
            out[name] = (interp, values)

        for name, width in wanted.items():
            pv = api.GetPrimvar(name)
            if not pv or not pv.HasAuthoredValue():
                continue
            raw = pv.Get(self.time)
            if raw is None:
                continue
            values = np.asarray(raw, np.float32).reshape(-1, width)
            idx = pv.GetIndices(self.time)
            if idx is not None and len(idx):
                idx = np.asarray(idx, np.int64)
                if idx.min() < 0 or idx.max() >= len(values):
                    self.warn(f"{mesh.GetPath()}: primvar {name} has an index out of range; left out")
                    continue
                values = values[idx]
            accept(name, str(pv.GetInterpolation()), values)
        pv = api.GetPrimvar("normals")
        if pv and pv.HasAuthoredValue():
            values = np.asarray(pv.ComputeFlattened(self.time), np.float32).reshape(-1, 3)
            accept("normals", str(pv.GetInterpolation()), values)
        else:
            attr = mesh.GetNormalsAttr()
            raw = attr.Get(self.time) if attr.HasAuthoredValue() else None
            if raw is not None and len(raw):
                accept("normals", str(mesh.GetNormalsInterpolation()), np.asarray(raw, np.float32).reshape(-1, 3))
        return out

    # -- points, curves, instancers ----------------------------------------------------
    def points(self, points: Any, material: list[Any]) -> list[Any]:
        p = np.asarray(points.GetPointsAttr().Get(self.time) or [], np.float32).reshape(-1, 3)
        if len(p) == 0:
            return []
        widths = points.GetWidthsAttr().Get(self.time)
        sizes = None
        if widths is not None and len(widths) == len(p):
            sizes = np.asarray(widths, np.float32)
        colors = self.vertex_colors(points, len(p))
        return [*material, PointSet(p, colors=colors, sizes=sizes)]

    def curves(self, curves: Any, material: list[Any]) -> list[Any]:
        p = np.asarray(curves.GetPointsAttr().Get(self.time) or [], np.float32).reshape(-1, 3)
        counts = np.asarray(curves.GetCurveVertexCountsAttr().Get(self.time) or [], np.int64)
        if len(p) < 2 or len(counts) == 0 or counts.sum() != len(p):
            return []
        if str(curves.GetTypeAttr().Get()) != "linear":
            self.warn(f"{curves.GetPath()}: cubic curves are drawn as lines through their control vertices")
        starts = np.cumsum(counts) - counts
        seg_counts = np.maximum(counts - 1, 0)
        if str(curves.GetWrapAttr().Get()) == "periodic":
            seg_counts = counts
        first = np.repeat(starts, seg_counts) + (
            np.arange(seg_counts.sum()) - np.repeat(np.cumsum(seg_counts) - seg_counts, seg_counts)
        )
        second = first + 1
        curve = np.repeat(np.arange(len(counts)), seg_counts)
        wrap = second >= starts[curve] + counts[curve]
        second[wrap] = starts[curve][wrap]
        segments = np.stack([first, second], axis=1)
        colors = self.vertex_colors(curves, len(p))
        return [*material, LineSet(p, indices=segments, colors=colors)]

    def vertex_colors(self, gprim: Any, count: int) -> np.ndarray | None:
        pv = gprim.GetDisplayColorPrimvar()
        if not pv or not pv.HasAuthoredValue() or str(pv.GetInterpolation()) not in ("vertex", "varying"):
            return None
        values = np.asarray(pv.ComputeFlattened(self.time), np.float64).reshape(-1, 3)
        return _srgb(values).astype(np.float32) if len(values) == count else None

    def instancer(self, instancer: Any) -> list[Node]:
        """One InstanceSet per shape of each prototype, placed by the instancer's arrays (vectorised)."""
        where = str(instancer.GetPath())
        targets = instancer.GetPrototypesRel().GetTargets()
        proto_indices = np.asarray(instancer.GetProtoIndicesAttr().Get(self.time) or [], np.int64)
        n = len(proto_indices)
        if n == 0 or not targets:
            return []
        matrices = self.instance_matrices(instancer, n)
        visible = np.ones(n, bool)
        mask = instancer.ComputeMaskAtTime(self.time)
        if mask:
            visible &= np.asarray(mask, bool)
        invisible = instancer.GetInvisibleIdsAttr().Get(self.time)
        if invisible is not None and len(invisible):
            ids = instancer.GetIdsAttr().Get(self.time)
            ids = np.asarray(ids, np.int64) if ids is not None and len(ids) == n else np.arange(n)
            visible &= ~np.isin(ids, np.asarray(invisible, np.int64))
        colors = None
        pv = self.UsdGeom.PrimvarsAPI(instancer.GetPrim()).GetPrimvar("displayColor")
        if pv and pv.HasAuthoredValue() and str(pv.GetInterpolation()) in ("vertex", "varying"):
            values = np.asarray(pv.ComputeFlattened(self.time), np.float64).reshape(-1, 3)
            colors = _srgb(values).astype(np.float32) if len(values) == n else None
        out = []
        for p, target in enumerate(targets):
            rows = np.flatnonzero(proto_indices == p)
            proto = self.stage.GetPrimAtPath(target)
            if len(rows) == 0 or not proto:
                continue
            for k, (local, attrs, shape) in enumerate(self.leaves(proto, np.eye(4))):
                placed = matrices if len(rows) == n else matrices[rows]
                transforms = placed if np.array_equal(local, np.eye(4)) else placed @ local
                item = InstanceSet(
                    shape,
                    transforms,
                    colors=None if colors is None else (colors if len(rows) == n else colors[rows]),
                    visible=None if visible[rows].all() else visible[rows],
                )
                name = _node_name(proto.GetName()) + (f"-{k}" if k else "")
                out.append(Node(name, [*attrs, item]))
        if (proto_indices < 0).any() or (proto_indices >= len(targets)).any():
            self.warn(f"{where}: protoIndices out of range are left out")
        return out

    def instance_matrices(self, instancer: Any, n: int) -> np.ndarray:
        """(N, 4, 4) column-vector matrices T * R * S of the instances (prototype roots' own xforms excluded)."""
        positions = instancer.GetPositionsAttr().Get(self.time)
        t = np.zeros((n, 3)) if positions is None or len(positions) != n else np.asarray(positions, np.float64)
        m = np.zeros((n, 4, 4))
        m[:, 3, 3] = 1.0
        orientations = (
            instancer.GetOrientationsfAttr().Get(self.time) if hasattr(instancer, "GetOrientationsfAttr") else None
        )
        if orientations is None or len(orientations) != n:
            orientations = instancer.GetOrientationsAttr().Get(self.time)
        if orientations is not None and len(orientations) == n:
            q = _quaternions(orientations)  # (w, x, y, z)
            q /= np.maximum(np.sqrt(np.einsum("ij,ij->i", q, q)), 1e-300)[:, None]
            w, x, y, z = q.T
            m[:, 0, 0], m[:, 0, 1], m[:, 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
            m[:, 1, 0], m[:, 1, 1], m[:, 1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
            m[:, 2, 0], m[:, 2, 1], m[:, 2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
        else:
            m[:, 0, 0] = m[:, 1, 1] = m[:, 2, 2] = 1.0
        scales = instancer.GetScalesAttr().Get(self.time)
        if scales is not None and len(scales) == n:
            m[:, :3, :3] *= np.asarray(scales, np.float64)[:, None, :]
        m[:, :3, 3] = t
        return m

    def leaves(self, prim: Any, matrix: np.ndarray) -> list[tuple[np.ndarray, list[Any], Any]]:
        """(matrix relative to the prototype, attributes, shape) of every shape under a prototype prim."""
        UsdGeom = self.UsdGeom
        if not prim.IsActive():
            return []
        imageable = UsdGeom.Imageable(prim)
        if imageable and imageable.GetVisibilityAttr().Get(self.time) == UsdGeom.Tokens.invisible:
            return []
        if prim.IsA(UsdGeom.Xformable):
            matrix = matrix @ _gf(UsdGeom.Xformable(prim).GetLocalTransformation(self.time))
        out: list[tuple[np.ndarray, list[Any], Any]] = []
        if prim.IsA(UsdGeom.Gprim):
            self._collect(self.gprim(prim, str(prim.GetTypeName())), matrix, [], out)
        source = prim.GetPrototype() if prim.IsInstance() else prim
        for child in source.GetChildren():
            out += self.leaves(child, matrix)
        return out

    def _collect(self, items: list[Any], matrix: np.ndarray, attrs: list[Any], out: list) -> None:
        from ...core.component import Shape
        from ...core.transform import Transform

        attrs = list(attrs)
        for item in items:
            if isinstance(item, Transform):
                matrix = matrix @ item.matrix
            elif isinstance(item, Node):
                self._collect(list(item.items), matrix, attrs, out)
            elif isinstance(item, Shape):
                out.append((matrix, list(attrs), item))
            else:
                attrs.append(item)


def triangulate(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangulation of polygons with ``counts`` vertices: ((T, 3) face-vertex corners, (T,) face of each).

    Faces with fewer than 3 vertices give no triangle.  Vectorised: no loop over faces.
    """
    counts = np.asarray(counts, np.int64)
    n = len(counts)
    if n and counts.min() == counts.max() and counts[0] in (3, 4):  # all triangles or all quads: no searching
        if counts[0] == 3:
            return np.arange(3 * n, dtype=np.int64).reshape(n, 3), np.arange(n, dtype=np.int64)
        first = np.arange(0, 4 * n, 4, dtype=np.int64)[:, None]
        corners = (first + np.array([0, 1, 2, 0, 2, 3], np.int64)).reshape(-1, 3)
        return corners, np.repeat(np.arange(n, dtype=np.int64), 2)
    n_tris = np.maximum(counts - 2, 0)
    starts = np.cumsum(counts) - counts
    faces = np.repeat(np.arange(len(counts)), n_tris)
    k = np.arange(int(n_tris.sum()), dtype=np.int64) - np.repeat(np.cumsum(n_tris) - n_tris, n_tris)
    first = starts[faces]
    corners = np.stack([first, first + k + 1, first + k + 2], axis=1)
    return corners, faces


def _quaternions(values: Any) -> np.ndarray:
    """A Vt.QuathArray / QuatfArray as (N, 4) (w, x, y, z)."""
    try:
        a = np.asarray(values, np.float64).reshape(-1, 4)  # Gf quaternions are stored (i, j, k, real)
        return a[:, [3, 0, 1, 2]].copy()
    except (TypeError, ValueError):
        return np.array([[q.GetReal(), *q.GetImaginary()] for q in values], np.float64)


def _matrix(m: np.ndarray, prim: Any) -> Matrix:
    try:
        return Matrix(m)
    except ValueError as exc:
        raise USDImportError(f"load_usd: {prim.GetPath()}: {exc}") from None


def _node_name(name: str) -> str:
    cleaned = "".join(ch if ch.isprintable() and ch != "/" else "_" for ch in str(name))
    return cleaned or "prim"
