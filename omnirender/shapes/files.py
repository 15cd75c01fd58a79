"""MeshFile: a mesh stored in a file, read by the reader registered for its extension.

The declaration lives here; the readers live in :mod:`omnirender.formats`,
which registers them with :func:`register_mesh_reader` (shapes import only
core, data and geometry, never a file format).  The file is parsed lazily on
first use (``parts()``), once per version: a scene can name many files and pay
only for those an engine actually evaluates.
"""

from __future__ import annotations

import importlib
import logging
import os
import time
from collections.abc import Callable, Iterable
from typing import Any

from ..core.paths import PathPolicy
from .base import DeclaredShape, parameter
from .meshes import TriangleSet
from .trimeshes import is_trimesh, is_trimesh_scene

__all__ = ["MeshFile", "register_mesh_reader", "mesh_suffixes", "read_mesh"]

#: The key a reader of in-memory trimesh objects is registered under.
TRIMESH_OBJECT = "<trimesh>"

MeshReader = Callable[..., list[tuple[dict[str, Any] | None, TriangleSet]]]
_readers: dict[str, str | MeshReader] = {}


def register_mesh_reader(suffixes: Iterable[str], reader: str | MeshReader, *, override: bool = False) -> None:
    """Make ``om.MeshFile`` read files ending in ``suffixes`` with ``reader(path, *, policy, strict)``.

    The reader returns ``[(material, TriangleSet)]``; ``policy`` is the path
    policy (:class:`~omnirender.core.paths.PathPolicy`) the files the mesh file
    names must obey, ``strict`` asks it to raise instead of warning when it
    leaves content out (:mod:`omnirender.core.drops`).

    ``reader`` is a callable or a ``"module:function"`` string imported on
    first use.  ``TRIMESH_OBJECT`` as a suffix names the reader of trimesh
    objects passed instead of a path.
    """
    for suffix in suffixes:
        key = suffix.lower()
        if key in _readers and not override and _readers[key] != reader:
            raise ValueError(f"a mesh reader for {key!r} is already registered; pass override=True")
        _readers[key] = reader


def mesh_suffixes() -> tuple[str, ...]:
    """The file extensions ``om.MeshFile`` reads, in registration order."""
    return tuple(s for s in _readers if s != TRIMESH_OBJECT)


def read_mesh(
    path: Any, *, policy: PathPolicy | None = None, strict: bool = False
) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
    """The parts of the mesh file (or trimesh object) ``path`` through its registered reader."""
    if is_trimesh(path) or is_trimesh_scene(path):
        key = TRIMESH_OBJECT
    else:
        key = next((s for s in _readers if os.fspath(path).lower().endswith(s)), "")
    reader = _readers.get(key)
    if reader is None:
        raise ValueError(f"MeshFile: no reader for {path!r} (supported: {', '.join(mesh_suffixes())})")
    if isinstance(reader, str):
        module, _, name = reader.partition(":")
        reader = getattr(importlib.import_module(module), name)
    start = time.monotonic()
    parts = reader(path, policy=policy or PathPolicy(), strict=strict)
    seconds = time.monotonic() - start
    if seconds >= SLOW_LOAD:  # long work says what it did (the "omnirender" logger, see omnirender.progress)
        triangles = sum(len(ts.index_array()) for _, ts in parts)
        name = "a trimesh object" if key == TRIMESH_OBJECT else os.fspath(path)
        logging.getLogger("omnirender").info("loaded %s: %d triangles in %.1f s", name, triangles, seconds)
    return parts


#: Loading a mesh file for longer than this (seconds) is reported on the "omnirender" logger.
SLOW_LOAD = 1.0


class MeshFile(DeclaredShape):
    """A mesh file; ``parts()`` gives, per part, its material parameters (or None) and a TriangleSet.

    Supported: OBJ (+MTL), PLY, STL, OFF, glTF/GLB (node transforms applied).
    A missing file raises FileNotFoundError at construction; an unreadable or
    malformed one raises ValueError naming the path and the loader's reason
    when first used (``parts()``/``load()``).  ``path`` may also be a mesh
    trimesh already made (a ``trimesh.Trimesh`` or ``trimesh.Scene``): it is
    used as it is (scene files cannot hold it; ``om.embed_files`` turns it into
    triangle sets).

    Material parameters are dicts: ``{"kind": "phong", "ambient", "diffuse",
    "specular", "shininess", "opacity"}`` (OBJ/MTL) or ``{"kind": "pbr",
    "base_color", "metallic", "roughness", "emission", "opacity"}`` (glTF),
    colours as RGB tuples in [0, 1]; the simplifier turns them into
    ``om.Material`` / ``om.PBRMaterial``.  A part's texture image, when the
    file has one, is under ``"texture"`` as an (H, W, 4) uint8 array.  glTF
    files are read with the full importer (``om.load_gltf``: every material
    slot, Draco, sparse accessors), flattened to world coordinates; their
    parts carry ``{"kind": "attributes", "attributes": [...]}``.

    ``trusted``, ``allowed_roots`` and ``strict`` set how the file's own
    references are read (see the module docs); they are the loader's options,
    not parameters of the shape (scene files do not store them: a scene file
    passes its own policy to the mesh files it names).
    """

    __slots__ = ("_path", "_policy", "_strict")
    _params = ("path",)
    #: Loader options a scene file may not set: it passes its own path policy (see :meth:`use_path_policy`).
    scene_file_excluded = frozenset({"trusted", "allowed_roots", "strict"})
    path = parameter("path", "Path of the mesh file.")

    def __init__(
        self,
        path: str | os.PathLike | Any,
        *,
        trusted: bool = False,
        allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
        strict: bool = False,
    ) -> None:
        object.__setattr__(self, "_policy", PathPolicy.of(trusted, allowed_roots))
        object.__setattr__(self, "_strict", bool(strict))
        super().__init__(path=path)

    def use_path_policy(self, policy: PathPolicy, strict: bool | None = None) -> None:
        """Read the file's references under ``policy`` from now on (scene files pass theirs)."""
        object.__setattr__(self, "_policy", policy)
        if strict is not None:
            object.__setattr__(self, "_strict", bool(strict))
        self._cache.pop("parts", None)

    def _validate(self, p: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
        path = p["path"]
        if is_trimesh(path) or is_trimesh_scene(path):
            return {"path": path}, {}
        if not isinstance(path, (str, os.PathLike)):
            raise ValueError(
                f"MeshFile: path must be a file name (str or os.PathLike) or a trimesh mesh, got {type(path).__name__}"
            )
        if "\x00" in os.fspath(path):
            raise ValueError("MeshFile: path must not contain a NUL character")
        path = os.fspath(path)
        if not os.path.exists(path):
            raise FileNotFoundError(f"MeshFile: no such file {path!r}")
        if not os.path.isfile(path):
            raise ValueError(f"MeshFile: {path!r} is not a file")
        suffixes = mesh_suffixes()
        if not path.lower().endswith(suffixes):
            raise ValueError(f"MeshFile: {path!r} has an unsupported extension (supported: {', '.join(suffixes)})")
        return {"path": path}, {}

    def load(self) -> None:
        """Parse the file now (otherwise done on first use); raises ValueError when it is malformed."""
        self.parts()

    def parts(self) -> list[tuple[dict[str, Any] | None, TriangleSet]]:
        """[(material parameters or None, TriangleSet)] per part, in file order; cached per version."""
        return self._cached("parts", lambda: read_mesh(self._path, policy=self._policy, strict=self._strict))

    @property
    def triangle_count(self) -> int:
        return sum(ts.triangle_count for _, ts in self.parts())
