"""The dependency rule around formats/: declarations never import a file format, formats register themselves."""

from __future__ import annotations

import ast
from pathlib import Path

import omnirender as om
from omnirender.scene.readers import scene_reader
from omnirender.shapes.files import mesh_suffixes

PACKAGE = Path(om.__file__).parent


def _imported(path: Path) -> set[str]:
    """Package-relative modules a file imports (anywhere in it, lazy imports included), as 'pkg.sub'."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = list(parts[: len(parts) - node.level])
            if node.module:
                found.add([*base, *node.module.split(".")][0])
            else:
                found.update([*base, alias.name][0] for alias in node.names)
    return found


#: The deliberate, lazy exceptions docs/NOTES.md documents (simplifiers building attributes and transient nodes).
EXCEPTIONS = {
    "shapes/simplifiers.py": {"attributes"},
    "shapes/csg_simplifier.py": {"attributes"},
    "shapes/instances.py": {"attributes", "scene"},
}


def test_shapes_core_data_import_no_format_animation_or_adapter():
    allowed = {"shapes": {"shapes", "core", "data", "geometry"}, "core": {"core"}, "data": {"data"}}
    for package, ok in allowed.items():
        for path in (PACKAGE / package).rglob("*.py"):
            bad = _imported(path) - ok - EXCEPTIONS.get(str(path.relative_to(PACKAGE)), set())
            assert not bad, f"{path.relative_to(PACKAGE)} imports {sorted(bad)}"


def test_animation_and_scene_never_import_formats():
    for package in ("animation", "scene", "techniques", "render.py"):
        paths = [PACKAGE / package] if package.endswith(".py") else (PACKAGE / package).rglob("*.py")
        for path in paths:
            assert "formats" not in _imported(path), path


def test_formats_register_readers_and_exporters():
    assert {".obj", ".ply", ".stl", ".off", ".gltf", ".glb"} <= set(mesh_suffixes())
    assert scene_reader("a.glb") is om.load_gltf
    assert {".glb", ".rib", ".html"} <= set(om.exporters())
    assert callable(om.export)
