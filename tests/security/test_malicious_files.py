"""The malicious files of tests/data_files/malicious: every one gives a clear error or a warning, none reads outside.

Each file is loaded the way an application would (``om.load_gltf``,
``om.MeshFile(...).load()``, ``om.load`` and then every mesh file and texture
of the scene) while an audit hook (:func:`sys.addaudithook`) records every
file the process opens: none may lie outside the malicious files' folder
(library files of Python and its packages excepted).  ``manifest.json`` says
what each file must give; ``make_malicious.py`` regenerates them.
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from pathlib import Path

import pytest

import omnirender as om

HERE = Path(__file__).resolve().parents[1] / "data_files" / "malicious"
FILES = (HERE / "files").resolve()
MANIFEST = json.loads((HERE / "manifest.json").read_text())
#: Exceptions that mean a crash rather than a clear refusal.
CRASHES = (RecursionError, MemoryError, KeyError, TypeError, IndexError, AttributeError, ZeroDivisionError)

_OPENED: list[str] | None = None


def _audit(event: str, args: tuple) -> None:
    if _OPENED is not None and event == "open" and isinstance(args[0], (str, bytes, os.PathLike)):
        _OPENED.append(os.fsdecode(args[0]))


sys.addaudithook(_audit)


def _library_roots() -> tuple[str, ...]:
    roots = {sys.prefix, sys.base_prefix, sys.exec_prefix, os.path.dirname(om.__file__), "/usr/lib", "/usr/share"}
    roots |= {"/usr/local/lib", "/proc", "/sys", "/dev", "/etc/ld.so.cache", "/lib", "/usr/lib64"}
    return tuple(os.path.realpath(r) for r in roots)


def _outside_reads(opened: list[str]) -> list[str]:
    libraries = _library_roots()
    bad = []
    for path in opened:
        real = os.path.realpath(path)
        inside = real == str(FILES) or real.startswith(str(FILES) + os.sep)
        library = any(real == r or real.startswith(r + os.sep) for r in libraries)
        if not inside and not library or "/outside/" in real or real.startswith("/etc/passwd"):
            bad.append(real)
    return bad


def _load(name: str, loader: str, strict: bool = False) -> None:
    path = FILES / name
    if loader == "gltf":
        om.load_gltf(path, strict=strict)
    elif loader == "mesh":
        om.MeshFile(path, strict=strict).load()
    else:
        root = om.load(path)
        for component in _components(root):
            if isinstance(component, om.MeshFile):
                component.load()
            elif isinstance(component, om.Texture):
                component.image_array()


def _components(node: om.Node) -> list:
    out, stack, seen = [], [node], set()
    while stack:
        current = stack.pop()
        if id(current) in seen:
            continue
        seen.add(id(current))
        for item in current.items:
            (stack if isinstance(item, om.Node) else out).append(item)
    return out


def _import_loaders() -> None:
    """Import what the loaders import lazily, so that the audit sees the files' reads, not module imports."""
    import PIL.Image
    import trimesh  # noqa: F401

    PIL.Image.init()
    om.load_gltf(HERE.parent / "two_parts.glb")
    om.MeshFile(HERE.parent / "textured.obj").load()
    om.MeshFile(HERE.parent / "cube.ply").load()


@pytest.mark.parametrize("name", sorted(MANIFEST))
def test_a_malicious_file_gives_a_clear_error_or_a_warning_and_reads_nothing_outside(name):
    global _OPENED
    case = MANIFEST[name]
    _import_loaders()
    opened: list[str] = []
    _OPENED = opened
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if case["expect"] == "error":
                with pytest.raises(Exception, match=case["match"]) as info:
                    _load(name, case["loader"])
                assert not isinstance(info.value, CRASHES), f"{name}: a crash, not a clear error: {info.value!r}"
                assert isinstance(info.value, (ValueError, OSError)), f"{name}: {info.value!r}"
                assert name in str(info.value) or str(FILES) in str(info.value), f"the error names the file: {info}"
            else:
                _load(name, case["loader"])
                drops = [str(w.message) for w in caught if issubclass(w.category, om.DroppedContentWarning)]
                assert any(__import__("re").search(case["match"], d) for d in drops), f"{name}: {drops}"
                assert all(name in d for d in drops), drops
                with pytest.raises(om.DroppedContentError, match=case["match"]):
                    _load(name, case["loader"], strict=True)
    finally:
        _OPENED = None
    assert _outside_reads(opened) == [], f"{name} made the loader open files outside its folder"


def test_the_audit_sees_a_read_outside():
    """The audit hook works: a trusted load of a traversing file opens the outside file and is caught."""
    global _OPENED
    _import_loaders()
    opened: list[str] = []
    _OPENED = opened
    try:
        om.load_gltf(FILES / "gltf-buffer-traversal.gltf", trusted=True)
    finally:
        _OPENED = None
    assert any(p.endswith("secret.bin") for p in _outside_reads(opened))


def test_allowed_roots_let_a_reference_out_and_only_there():
    node = om.load_gltf(FILES / "gltf-buffer-traversal.gltf", allowed_roots=[HERE / "outside"])
    assert om.bounds(node) is not None
    with pytest.raises(om.UntrustedReferenceError, match="absolute path"):
        om.load_gltf(FILES / "gltf-buffer-etc-passwd.gltf", allowed_roots=[HERE / "outside"])
