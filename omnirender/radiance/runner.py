"""Running the Radiance programs: found through pyradiance, no shell, a timeout, progress, Radiance's errors.

The PyPI package ``pyradiance`` ships ``oconv``, ``rpict``, ``rtrace``,
``obj2mesh``, ``pvalue`` ... in its ``bin/`` folder and Radiance's function
files (``rayinit.cal``) in ``lib/``.  The programs are taken from there, never
from the user's PATH, and run with ``RAYPATH`` = the working folder, then
pyradiance's ``lib``, then any ``RAYPATH`` the user had.  pyradiance is located
without importing it (its import changes ``PATH`` and ``RAYPATH`` for the whole
process).  ``rpict -t`` reports ``... 45.00% after ...`` on stderr, which
:func:`omnirender.process.run_watched` turns into a progress bar (tqdm on a
terminal) or calls to a ``(done, total)`` callback, as for POV-Ray.
"""

from __future__ import annotations

import importlib.util
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..core import OmnirenderError
from ..process import ProgramTimeout, killed_by, progress_reporter, run_watched

__all__ = ["RadianceError", "radiance_paths", "program", "run", "error_lines", "INSTALL"]

INSTALL = "install it with: pip install 'omnirender[radiance]' (the PyPI package pyradiance ships the programs)"
_PROGRESS = re.compile(rb"(\d+(?:\.\d+)?)% after")
_ERROR = re.compile(r"(?i)\b(fatal|error|system|user|internal|consistency)\b|cannot|bad |undefined|missing")


class RadianceError(OmnirenderError, RuntimeError):
    """A Radiance program is missing, failed or timed out; the message carries Radiance's own lines."""

    def __init__(self, message: str, output: str = "") -> None:
        super().__init__(message)
        self.output = output


def radiance_paths() -> tuple[Path, Path] | None:
    """(``bin`` folder, ``lib`` folder) of the installed pyradiance, or None when it is not installed."""
    try:
        spec = importlib.util.find_spec("pyradiance")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    root = Path(next(iter(spec.submodule_search_locations)))
    return root / "bin", root / "lib"


def program(name: str) -> Path:
    """The path of Radiance program ``name`` inside pyradiance; RadianceError with the fix when missing."""
    paths = radiance_paths()
    if paths is None:
        raise RadianceError(f"Radiance: the pyradiance package is not installed; {INSTALL}")
    exe = paths[0] / name
    if not (exe.is_file() and os.access(exe, os.X_OK)):
        raise RadianceError(f"Radiance: the program {name!r} is missing from pyradiance ({paths[0]}); {INSTALL}")
    return exe


def environment() -> dict[str, str]:
    """The environment Radiance programs run in: pyradiance's ``bin`` first on PATH, ``RAYPATH`` = ``.``, ``lib``."""
    paths = radiance_paths()
    env = dict(os.environ)
    if paths is None:
        return env
    bin_dir, lib_dir = paths
    user = [p for p in os.environ.get("RAYPATH", "").split(os.pathsep) if p and p not in (".", str(lib_dir))]
    env["RAYPATH"] = os.pathsep.join([".", str(lib_dir), *user])
    env["PATH"] = os.pathsep.join([str(bin_dir), os.environ.get("PATH", "")])
    return env


def error_lines(output: str) -> list[str]:
    """Radiance's own error and warning lines (``oconv: fatal - ...``), at most 12."""
    lines = [ln.strip() for ln in output.replace("\r", "\n").split("\n") if ln.strip()]
    lines = [ln for ln in lines if not _PROGRESS.search(ln.encode()) and _ERROR.search(ln)]
    return lines[-12:]


def run(
    name: str,
    args: Sequence[str],
    cwd: str | os.PathLike[str],
    *,
    stdin: str | os.PathLike[str] | None = None,
    stdout: str | os.PathLike[str] | None = None,
    timeout: float | None = 600.0,
    total: float | None = None,
    progress: Any = False,
    pixels: int = 0,
    what: str = "",
) -> str:
    """Run Radiance program ``name`` with ``args`` in ``cwd``; returns its stderr text or raises RadianceError.

    ``stdin``/``stdout`` are files (in ``cwd``) the program reads from and
    writes to, so no pipe can fill up.  ``progress`` (False, None for a bar
    on a terminal, True, or a callable ``(done, total)``) gets ``rpict``'s
    percentage reports as pixels of ``pixels``.  ``timeout`` in seconds (None:
    no limit); on expiry the program is killed and the message names ``total``
    (the whole job's timeout this program had a share of) or ``timeout``.
    ``what`` says what was running (for messages).
    """
    exe = program(name)
    label = f"{name} ({what})" if what else name
    update, close = progress_reporter(progress, pixels, "px", f"Radiance {name}")

    def watch(tail: bytes) -> None:
        found = _PROGRESS.findall(tail)
        if found:
            update(min(round(float(found[-1]) / 100.0 * pixels), pixels), pixels)

    folder = Path(cwd)
    try:
        with (
            open(folder / stdin, "rb") if stdin is not None else open(os.devnull, "rb") as fin,
            open(folder / stdout, "wb") if stdout is not None else open(os.devnull, "wb") as fout,
        ):
            returncode, raw = run_watched(
                [str(exe), *args], folder, env=environment(), stdin=fin, stdout=fout, timeout=timeout, watch=watch
            )
        if returncode == 0 and progress is not False:
            update(pixels, pixels)
    except OSError as exc:
        raise RadianceError(f"Radiance: cannot start {exe}: {exc}; {INSTALL}") from None
    except ProgramTimeout as exc:
        raise RadianceError(
            f"Radiance: {label} took longer than the timeout of {total or timeout:g} s and was stopped; "
            "pass a larger timeout=, a smaller size or cheaper om.radiance.Options (lower ab)",
            exc.output.decode("latin-1"),
        ) from None
    finally:
        close()
    output = raw.decode("latin-1")
    signal = killed_by(returncode)
    if signal is not None:
        raise RadianceError(f"Radiance: {label} was {signal}", output)
    if returncode != 0:
        lines = error_lines(output) or [output[-2000:].strip() or "(no message)"]
        detail = "\n  ".join(lines)
        raise RadianceError(f"Radiance: {label} failed (exit status {returncode}):\n  {detail}", output)
    return output
