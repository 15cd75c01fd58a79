"""Engine and exporter registries behind ``om.render``, ``om.export`` and ``om.engines``.

Adapters register themselves by name (engines) or file extension (exporters).
Built-in entries are named lazily as ``"module:function"`` so that nothing is
imported until it is used; third-party packages call :func:`register_engine`
or :func:`register_exporter` with callables.  ``om.engines()`` reports which
engines work on this machine and why the others do not: an engine declares
the Python packages it needs (found without importing them) with the pip
extra that installs them, and the Debian package of an external program, so
a missing piece is named together with the command that installs it.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = [
    "render",
    "export",
    "engines",
    "engine_status",
    "install_commands",
    "register_engine",
    "unregister_engine",
    "register_exporter",
    "EngineEntry",
    "exporters",
]


@dataclass
class EngineEntry:
    """A named engine: its render function, availability check, origin and what it needs installed.

    ``needs`` lists ``(module, pip package)`` pairs, ``extra`` the pip extra of
    omnirender that installs them, ``debian`` the Debian package of an
    external program it runs (its availability check finds the program).
    """

    name: str
    render: str | Callable[..., Any]
    available: str | Callable[[], tuple[bool, str]] | None
    description: str
    origin: str
    needs: tuple[tuple[str, str], ...] = ()
    extra: str | None = None
    debian: str | None = None


_engines: dict[str, EngineEntry] = {}
_exporters: dict[str, tuple[str | Callable[..., Any], str]] = {}


def _resolve(ref: str | Callable[..., Any]) -> Callable[..., Any]:
    if callable(ref):
        return ref
    module, _, attr = ref.partition(":")
    return getattr(importlib.import_module(module), attr)


def register_engine(
    name: str,
    render_fn: str | Callable[..., Any],
    available: str | Callable[[], tuple[bool, str]] | None = None,
    description: str = "",
    *,
    override: bool = False,
    needs: tuple[tuple[str, str], ...] = (),
    extra: str | None = None,
    debian: str | None = None,
) -> None:
    """Make ``om.render(scene, engine=name)`` call ``render_fn(scene, size=..., **options)``.

    ``needs`` names the Python modules the engine imports as ``(module, pip
    package)`` pairs and ``extra`` the pip extra installing them (reported
    with ``pip install 'omnirender[extra]'`` when one is missing); ``debian``
    the Debian package of an external program it runs.
    """
    if name in _engines and not override:
        raise ValueError(
            f"an engine named {name!r} is already registered (from {_engines[name].origin}); pass override=True"
        )
    origin = render_fn if isinstance(render_fn, str) else getattr(render_fn, "__module__", "?")
    _engines[name] = EngineEntry(name, render_fn, available, description, str(origin), tuple(needs), extra, debian)


def unregister_engine(name: str) -> None:
    """Remove the engine called ``name`` (no error when it is not registered)."""
    _engines.pop(name, None)


def register_exporter(
    extension: str, export_fn: str | Callable[..., Any], description: str = "", *, override: bool = False
) -> None:
    """Make ``om.export(scene, "x" + extension)`` call ``export_fn(scene, path, **options)``."""
    ext = extension.lower() if extension.startswith(".") else "." + extension.lower()
    if ext in _exporters and not override:
        raise ValueError(f"an exporter for {ext!r} is already registered; pass override=True")
    _exporters[ext] = (export_fn, description)


def engines() -> dict[str, tuple[bool, str]]:
    """Every registered engine name -> (available here, reason or description).

    A missing Python package is reported with the pip command that installs it.
    """
    return {name: engine_status(name) for name in _engines}


def missing_packages(entry: EngineEntry) -> list[str]:
    """The pip packages of ``entry.needs`` whose module cannot be found here (nothing is imported)."""
    missing = []
    for module, package in entry.needs:
        try:
            spec = importlib.util.find_spec(module)
        except (ImportError, ValueError):
            spec = None
        # a folder named like the module (a namespace package, e.g. a test folder) is not the package
        if spec is None or spec.origin in (None, "namespace"):
            missing.append(package)
    return missing


def engine_status(name: str, check: bool = True) -> tuple[bool, str]:
    """(available, reason) of one engine: its Python packages, then (``check``) the adapter's own check.

    ``check=False`` looks for the packages only (fast: nothing is imported or
    started); the adapter's check may create a GL context or run a program.
    """
    entry = _engines.get(name)
    if entry is None:
        raise ValueError(f"unknown engine {name!r}; registered engines: {sorted(_engines)}")
    missing = missing_packages(entry)
    if missing:
        fix = f"pip install 'omnirender[{entry.extra}]'" if entry.extra else f"pip install {' '.join(missing)}"
        return False, f"needs the Python package{'s' if len(missing) > 1 else ''} {', '.join(missing)}: {fix}"
    if entry.available is None or not check:
        return True, entry.description
    try:
        ok, why = _resolve(entry.available)()
    except Exception as exc:  # an adapter that cannot even be imported is unavailable
        ok, why = False, f"{type(exc).__name__}: {exc}"
    return ok, why or entry.description


def install_commands(names: Iterable[str]) -> list[str]:
    """The commands that install what the engines ``names`` lack: one pip command, one apt-get command."""
    extras: list[str] = []
    debian: list[str] = []
    for name in names:
        entry = _engines.get(name)
        if entry is None:
            continue
        if missing_packages(entry) and entry.extra and entry.extra not in extras:
            extras.append(entry.extra)
        elif entry.debian and entry.debian not in debian:
            debian.append(entry.debian)
    commands = []
    if extras:
        commands.append(f"pip install 'omnirender[{','.join(extras)}]'")
    if debian:
        commands.append(f"sudo apt-get install {' '.join(debian)}")
    return commands


def exporters() -> dict[str, str]:
    """Supported export extensions -> description."""
    return {ext: desc for ext, (_, desc) in sorted(_exporters.items())}


def render(
    scene: Any,
    engine: str = "gl",
    size: tuple[int, int] = (640, 480),
    mask: str | None = None,
    tile: int | None = None,
    **options: Any,
) -> Any:
    """Render ``scene`` with the engine called ``engine``; returns an :class:`om.Image`.

    ``scene`` is an ``om.Node`` (or a list of components); its first camera
    is used.  Objects with ``as_scene(engine, size)`` (renderer trees of
    ``om.compositing``) are rendered as the scene graph that method returns.
    ``engine`` is ``"gl"``, ``"povray"``, ``"mitsuba"``, ``"radiance"`` or any name
    given to :func:`register_engine`; ``om.engines()`` tells which work here
    and why not the others.  ``size`` is ``(width, height)`` in pixels.
    ``mask`` is a group-mask expression (``"!debug & (left | shared)"``):
    nodes whose groups do not match it are skipped.  Other options go to the
    engine, which refuses the ones it does not know (see ``help()`` of
    ``om.gl.render``, ``om.povray.render``, ``om.mitsuba.render``, ``om.radiance.render``):

    - gl: ``samples`` (MSAA, 0/1/2/4/8/16), ``background``, ``read_depth``, ``shadows`` (default True),
      ``pipeline`` (``"forward"`` or ``"deferred"``);
    - povray: ``quality`` (0..11), ``antialias``, ``timeout``, ``threads``, ``keep``, ``depth``;
    - mitsuba: ``quality`` (``"preview"``, the default: a few samples, denoised; ``"final"``), ``spp``
      (samples per pixel), ``denoise``, ``integrator`` (a Mitsuba plugin dict), ``seed``, ``rfilter``,
      ``depth``, ``headlight``, ``global_ambient``;
    - radiance: ``options`` (an ``om.radiance.Options``), ``oversample``, ``exposure``, ``timeout``, ``progress``,
      ``keep``, ``headlight``, ``global_ambient``;
    - every engine: ``on_missing`` (``"raise"``, ``"warn"`` or ``"skip"`` for shapes no handler can draw).

    ``tile`` renders the image as tiles of at most ``tile`` x ``tile`` pixels
    with off-axis projections and stitches them (:mod:`omnirender.tiling`):
    the GL engine does so by itself when ``size`` is beyond its framebuffer
    limit; the other engines refuse ``tile=``.  :func:`om.render_to_file`
    streams tiles into a PNG file for posters larger than memory.

    The returned image has ``.array`` (H, W, 4) uint8 sRGB, ``.depth``
    (eye-space distance, inf on the background, or None), ``.mask``,
    ``.pixel(x, y)`` and ``.save(path)``.
    """
    entry = _engines.get(engine)
    if entry is None:
        from .options import did_you_mean

        raise ValueError(
            f"unknown engine {engine!r}; registered engines: {sorted(_engines)}{did_you_mean(engine, _engines)}"
        )
    size = _check_size(size)
    as_scene = getattr(scene, "as_scene", None)
    if callable(as_scene):  # not a scene graph but drawn by one (a renderer tree)
        scene = as_scene(engine, size)
    _check_scene(f"om.render(engine={engine!r})", scene)
    _warn_if_empty(f"om.render(engine={engine!r})", scene)
    if tile is None and engine == "gl" and max(size) > 4096:
        from .tiling import MAX_TILED_PIXELS, needs_tiles

        if size[0] * size[1] <= MAX_TILED_PIXELS:  # larger: refused before any context is made
            tile = needs_tiles(engine, size, options.get("samples", 4))
    if tile is not None:
        from .tiling import render_tiled

        return render_tiled(scene, engine, size, tile, mask=mask, **options)
    if mask is not None:
        options["mask"] = mask
    # the GL engine fits the same camera to what it compiled; the others get it in a stand-in root node
    viewed = scene if engine == "gl" else with_fitted_camera(scene, size, mask)
    try:
        return _resolve(entry.render)(viewed, size=size, **options)
    finally:
        if viewed is not scene:
            viewed.clear()  # the stand-in lets go of the scene's nodes and components again


def with_fitted_camera(scene: Any, size: tuple[int, int], mask: str | None = None) -> Any:
    """``scene``, or, when it has no camera, a node holding ``Camera.fitted`` to its bounds and the scene.

    Every engine then shows a scene without a camera the way the GL engine
    does (the GL engine fits the same camera itself).
    """
    from .core.camera import Camera
    from .core.component import RenderingComponent
    from .core.mask import compile_mask
    from .scene.node import Node
    from .techniques.bounds import bounds

    if isinstance(scene, Node):
        node = scene
    else:
        node = Node("scene", [scene] if isinstance(scene, RenderingComponent) else list(scene))
    if node.declarations(None if mask is None else compile_mask(mask)).camera is not None:
        return scene
    box = bounds(node, mask=mask)
    if box is None:
        return scene
    # the same name and items (child nodes keep their first parent, so their paths do not change)
    return Node(node.name, [Camera.fitted(box, size), *node.items])


def export(scene: Any, path: str | os.PathLike[str], **options: Any) -> Path:
    """Write ``scene`` to ``path`` with the exporter chosen by its extension."""
    p = Path(path)
    ext = p.suffix.lower()
    found = _exporters.get(ext)
    if found is None:
        raise ValueError(f"cannot export to {p.name!r}: unknown extension {ext!r}; supported: {sorted(_exporters)}")
    _check_scene(f"om.export({p.name!r})", scene)
    _resolve(found[0])(scene, p, **options)
    return p


def _check_scene(function: str, scene: Any) -> None:
    """TypeError naming the fix unless ``scene`` is a Node or an iterable of components.

    Checked here so that ``om.render(None)`` or ``om.render(5)`` fail with one
    clear message instead of deep inside an adapter (or, worse, render an
    empty image).
    """
    from .core.component import RenderingComponent

    if hasattr(scene, "_compile_node") or isinstance(scene, RenderingComponent):
        return
    fix = "pass an om.Node (e.g. om.Node('scene', [...])) or a list of shapes and attributes"
    if isinstance(scene, (str, bytes)) or not isinstance(scene, Iterable):
        raise TypeError(f"{function}: scene must be an om.Node or a list of components, got {scene!r:.60}; {fix}")
    if not isinstance(scene, (list, tuple)):
        return  # other iterables (generators) are checked by the adapter; iterating here would consume them
    for i, item in enumerate(scene):
        if not isinstance(item, RenderingComponent) and not hasattr(item, "_compile_node"):
            raise TypeError(f"{function}: scene[{i}] is a {type(item).__name__} ({item!r:.60}), not a component; {fix}")


def _warn_if_empty(function: str, scene: Any) -> None:
    """Warn when ``scene`` holds nothing but attributes (no shape): the image would show only the background.

    Components that are neither shapes nor attributes (techniques, a renderer tree's drawing component)
    may draw by themselves: a scene holding one is not reported.
    """
    import warnings

    from .core.component import Attribute, Shape
    from .scene.node import Node

    stack, seen = [scene], set()
    while stack:
        current = stack.pop()
        draws = hasattr(current, "parameters") and not isinstance(current, (Attribute, Node))
        if isinstance(current, Shape) or draws:
            return
        if isinstance(current, Node):
            if id(current) not in seen:
                seen.add(id(current))
                stack.extend(current.items)
        elif isinstance(current, (list, tuple)):
            stack.extend(current)
        elif not hasattr(current, "parameters"):
            return  # something else (a generator, a renderer tree's product): the adapter judges it
    warnings.warn(
        f"{function}: the scene holds no shapes, so the image shows only the background; add shapes "
        "(om.Sphere(), om.MeshFile(path), ...) to a node of the scene",
        stacklevel=3,
    )


def _check_size(size: Any) -> tuple[int, int]:
    from .options import check_image_size

    return check_image_size("om.render", size)


_PILLOW = ("PIL", "pillow")  # images are read and written with Pillow
register_engine(
    "gl", "omnirender.gl:render", "omnirender.gl:available", "OpenGL through moderngl (real time)",
    needs=(("moderngl", "moderngl"), _PILLOW), extra="gl",
)  # fmt: skip
register_engine(
    "povray", "omnirender.povray:render", "omnirender.povray:available", "POV-Ray 3.7 ray tracer",
    needs=(_PILLOW,), extra="povray", debian="povray",
)  # fmt: skip
register_engine(
    "mitsuba", "omnirender.mitsuba:render", "omnirender.mitsuba:available", "Mitsuba 3 path tracer",
    needs=(("mitsuba", "mitsuba"), _PILLOW), extra="mitsuba",
)  # fmt: skip
register_engine(
    "radiance", "omnirender.radiance:render", "omnirender.radiance:available", "Radiance (rpict, from pyradiance)",
    needs=(("pyradiance", "pyradiance"), _PILLOW), extra="radiance",
)  # fmt: skip
register_exporter(".pov", "omnirender.povray:export", "POV-Ray scene description")
register_exporter(".rad", "omnirender.radiance:export", "Radiance scene description (with .rtm meshes)")
