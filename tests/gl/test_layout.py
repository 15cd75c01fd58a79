"""The GL adapter's layout: one-way dependencies between its sub-packages, no import circles.

``gl/engine/`` holds the engine's internals and imports nothing else of ``gl``;
``gl/techniques/``, ``gl/deferred/`` and ``gl/post/`` build on it; the facade
``gl/glengine.py`` assembles them; ``gl/painters/`` register against the facade.
Imports inside functions count: a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
import importlib
import pathlib

import omnirender.gl as gl

GL = pathlib.Path(gl.__file__).parent

#: edges from the engine to a technique that are still to go (the compiler reads the deferred pipeline's material
#: descriptions); none may be added
KNOWN_INWARD = {
    ("omnirender.gl.engine.compiler", "omnirender.gl.deferred.models"),
}


def _modules() -> dict[str, pathlib.Path]:
    mods = {}
    for path in GL.rglob("*.py"):
        parts = ["omnirender", "gl", *path.relative_to(GL).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        mods[".".join(parts)] = path
    return mods


def _edges() -> dict[str, set[str]]:
    """Every module's imports of other ``omnirender.gl`` modules, function-level ones included."""
    mods = _modules()
    edges: dict[str, set[str]] = {name: set() for name in mods}
    for name, path in mods.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = ".".join(package[: len(package) - node.level + 1] + ([node.module] if node.module else []))
                else:
                    base = node.module or ""
                for alias in node.names:
                    target = f"{base}.{alias.name}" if f"{base}.{alias.name}" in mods else base
                    if target in mods and target != name:
                        edges[name].add(target)
            elif isinstance(node, ast.Import):
                edges[name].update(a.name for a in node.names if a.name in mods and a.name != name)
    return edges


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[2] if len(parts) > 2 else "gl"


def test_the_engine_package_imports_no_technique_painter_or_facade() -> None:
    inward = {
        (source, target)
        for source, targets in _edges().items()
        if _layer(source) == "engine"
        for target in targets
        if _layer(target) != "engine"
    }
    assert inward <= KNOWN_INWARD, f"gl/engine/ imports outside itself: {sorted(inward - KNOWN_INWARD)}"


def test_techniques_never_import_the_facade_or_the_painters() -> None:
    bad = {
        (source, target)
        for source, targets in _edges().items()
        if _layer(source) in ("techniques", "deferred", "post")
        for target in targets
        if _layer(target) in ("glengine", "painters", "gl")
    }
    assert not bad, f"techniques depend on what is built on them: {sorted(bad)}"


def test_the_facade_never_imports_the_painters() -> None:
    targets = _edges()["omnirender.gl.glengine"]
    assert not {t for t in targets if _layer(t) in ("painters", "gl")}, sorted(targets)


def test_no_import_circles() -> None:
    edges = _edges()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    circles: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in edges:
        if v not in index:
            visit(v)
    assert not circles, f"modules importing each other in a circle: {circles}"


def test_every_public_name_is_importable_from_om_gl() -> None:
    for name in gl.__all__:
        assert getattr(gl, name) is not None, name
    assert importlib.import_module("omnirender.gl.glengine").GLEngine is gl.GLEngine
