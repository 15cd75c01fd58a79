"""From a scene graph to the files Radiance reads: description, pictures, meshes, octree.

:func:`evaluate` runs a :class:`RadianceEngine` over the scene;
:func:`write_scene` writes its pictures, compiles its meshes with ``obj2mesh``
and writes the description into a folder; :func:`compile_octree` runs
``oconv``.  :func:`locate` adds the node that wrote the failing primitive to a
Radiance error.  Every program runs with a share of one deadline, so a whole
render or analysis respects its ``timeout``.
"""

from __future__ import annotations

import re
import time
from pathlib import Path
from typing import Any

from ..options import check_timeout
from . import painters as _painters  # noqa: F401  (registers the default handlers)
from .engine import RadianceEngine
from .picture import write_picture
from .runner import RadianceError, run

__all__ = ["as_node", "evaluate", "write_scene", "compile_octree", "locate", "Deadline", "ENGINE_OPTIONS"]

#: Keyword options passed on to the engine.
ENGINE_OPTIONS = {"mask", "on_missing", "technique", "resource_prefix"}
#: The options of ``om.radiance.render`` itself (for "did you mean" when an unknown one reaches the engine).
RENDER_OPTIONS = ("options", "oversample", "timeout", "progress", "keep", "global_ambient", "headlight", "exposure")


class Deadline:
    """The time left of one overall ``timeout`` (None: no limit), handed to each program in turn."""

    def __init__(self, timeout: float | None) -> None:
        timeout = check_timeout("Radiance", timeout)
        self.timeout = timeout
        self.end = None if timeout is None else time.monotonic() + float(timeout)

    def left(self) -> float | None:
        """Seconds left (at least a tiny positive amount, so an expired deadline still reports the timeout)."""
        if self.end is None:
            return None
        return max(self.end - time.monotonic(), 1e-3)

    def limits(self) -> dict[str, float | None]:
        """``timeout=`` (what is left) and ``total=`` (the whole timeout) for :func:`runner.run`."""
        return {"timeout": self.left(), "total": self.timeout}


def as_node(scene: Any) -> Any:
    """``scene`` itself when it is a node, else a node holding the components (evaluated more than once)."""
    if hasattr(scene, "preevaluate"):
        return scene
    from ..scene import Node

    return Node("scene", list(scene))


def evaluate(scene: Any, size: tuple[int, int], **options: Any) -> RadianceEngine:
    """A :class:`RadianceEngine` that has evaluated ``scene`` (a Node or a list of components)."""
    unknown = set(options) - ENGINE_OPTIONS - {"global_ambient", "headlight", "coverage", "shared"}
    if unknown:
        from ..options import options_hint

        raise TypeError(
            f"Radiance: unknown option(s) {sorted(unknown)}; the engine takes {sorted(ENGINE_OPTIONS)}"
            + options_hint(unknown, [*ENGINE_OPTIONS, *RENDER_OPTIONS])
        )
    engine = RadianceEngine(size, **options)
    engine.run(as_node(scene))
    return engine


def write_scene(engine: RadianceEngine, folder: Path, name: str, deadline: Deadline) -> list[Path]:
    """Write the pictures, the compiled meshes and the description ``name`` into ``folder``; returns the files."""
    text = engine.description()
    written = []
    for picture, data in engine.pictures:
        write_picture(folder / picture, data)
        written.append(folder / picture)
    for job in engine.meshes:
        stem = job.name[: -len(".rtm")]
        (folder / f"{stem}.obj").write_text(job.obj, encoding="ascii")
        args = ["-w"]
        if job.materials:
            (folder / f"{stem}.mat").write_text(job.materials, encoding="ascii")
            args += ["-a", f"{stem}.mat"]
        run("obj2mesh", [*args, f"{stem}.obj", job.name], folder, **deadline.limits(), what=_mesh_what(engine, job))
        for temporary in (f"{stem}.obj", f"{stem}.mat"):
            (folder / temporary).unlink(missing_ok=True)
        written.append(folder / job.name)
    (folder / name).write_text(text, encoding="ascii")
    written.append(folder / name)
    return written


def _mesh_what(engine: RadianceEngine, job: Any) -> str:
    return f"mesh {job.name} of node {job.node}" if job.node else f"mesh {job.name}"


def compile_octree(folder: Path, name: str, deadline: Deadline) -> str:
    """Run ``oconv`` on the description ``name`` in ``folder``; returns the octree's file name."""
    octree = Path(name).stem + ".oct"
    run("oconv", ["-f", name], folder, stdout=octree, **deadline.limits(), what="building the octree")
    return octree


_QUOTED = re.compile(r'"([^"\s]+)"')


def locate(exc: RadianceError, engine: RadianceEngine, keep: Any = None) -> None:
    """Add the nodes that wrote the primitives Radiance's message names (and the ``keep=`` hint) to ``exc``."""
    message = str(exc)
    found = []
    for name in _QUOTED.findall(message):
        node = engine.owners.get(name)
        if node is not None and (name, node) not in found:
            found.append((name, node))
    for name, node in found:
        message += f"\n  {name} was written for node {node}"
    if keep is None:
        message += "\n  (pass keep='<folder>' to keep scene.rad and its files for inspection)"
    exc.args = (message,)
