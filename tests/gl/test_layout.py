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

#: edges from the engine to a technique that are still to go; none may be added
KNOWN_INWARD: set[tuple[str, str]] = set()


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


#: private reads across modules that are justified; each entry is (module, attribute) with the reason beside it
PRIVATE_READS_ALLOWED: set[tuple[str, str]] = set()


def _own_private_names(tree: ast.AST) -> set[str]:
    """The private names a module defines itself: attributes it assigns, slots, class attributes, functions."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                names.add(node.attr)  # (``engine._x = ...`` is a write into another object: not its own)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.startswith("_"):
            names.add(node.value)  # __slots__ entries, object.__setattr__(self, "_name", ...)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
    return {n for n in names if n.startswith("_")}


def _private_reads() -> list[str]:
    """``x._name`` where ``x`` is not ``self``, ``cls`` or ``super()`` and the module does not define ``_name``;
    ``from module import _name`` of another module."""
    found = []
    for name, path in _modules().items():
        tree = ast.parse(path.read_text())
        own = _own_private_names(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute):
                attr = node.attr
                if not attr.startswith("_") or attr.startswith("__") or attr in own:
                    continue
                value = node.value
                if isinstance(value, ast.Name) and value.id in ("self", "cls"):
                    continue
                if isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "super":
                    continue
                if (name, attr) not in PRIVATE_READS_ALLOWED:
                    found.append(f"{path.relative_to(GL)}:{node.lineno}: {ast.unparse(node)}")
            elif isinstance(node, ast.ImportFrom) and node.module != "__future__":
                for alias in node.names:
                    if alias.name.startswith("_") and not alias.name.startswith("__"):
                        if (name, alias.name) not in PRIVATE_READS_ALLOWED:
                            found.append(f"{path.relative_to(GL)}:{node.lineno}: imports {alias.name}")
    return found


def test_no_module_reads_another_modules_private_attributes() -> None:
    """Collaborators talk through public methods: no ``other._state`` reads or writes across modules."""
    assert not _private_reads(), "private attributes of other modules used:\n" + "\n".join(_private_reads())


def test_the_scan_finds_a_private_read() -> None:
    tree = ast.parse("def f(engine):\n    engine._surface.append(1)\n    engine._dirty = True\n    self._own = 1\n")
    own = _own_private_names(tree)
    reads = [n for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr.startswith("_")]
    assert sorted(r.attr for r in reads if r.attr not in own) == ["_dirty", "_surface"]


def test_the_gl_engine_is_a_facade_over_collaborators_not_mixins() -> None:
    """``GLEngine`` derives from the core ``Engine`` alone; its compile and install sides are objects it holds."""
    from omnirender.core.engine import Engine
    from omnirender.gl.engine.compiler import DrawListCompiler
    from omnirender.gl.engine.dynamic import TransformUpdater
    from omnirender.gl.engine.renderer import BatchInstaller

    assert gl.GLEngine.__bases__ == (Engine,)
    for cls in (DrawListCompiler, TransformUpdater, BatchInstaller):
        assert not issubclass(gl.GLEngine, cls), cls
        assert cls.__init__ is not object.__init__, f"{cls.__name__} owns its state (made in its __init__)"
