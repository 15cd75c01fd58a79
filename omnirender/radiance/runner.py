"""Running the Radiance programs: found through pyradiance, no shell, a timeout, progress, Radiance's errors.

The PyPI package ``pyradiance`` ships ``oconv``, ``rpict``, ``rtrace``,
``obj2mesh``, ``pvalue`` ... in its ``bin/`` folder and Radiance's function
files (``rayinit.cal``) in ``lib/``.  The programs are taken from there, never
from the user's PATH, and run with ``RAYPATH`` = the working folder, then
pyradiance's ``lib``, then any ``RAYPATH`` the user had.  pyradiance is located
without importing it (its import changes ``PATH`` and ``RAYPATH`` for the whole
process).  ``rpict -t`` reports ``... 45.00% after ...`` on stderr; a reader
thread turns it into a progress bar (tqdm on a terminal) or calls a callback.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ..core import OmnirenderError

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


def _bar(progress: Any, label: str) -> tuple[Callable[[float], None], Callable[[], None]]:
    """(update(fraction), close()) for ``progress``: None (tqdm on a terminal), bool, or a callable(fraction)."""
    if callable(progress):
        return progress, lambda: None
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return (lambda fraction: None), lambda: None
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is in the radiance extra
        return (lambda fraction: None), lambda: None
    bar = tqdm(total=100, unit="%", desc=label, leave=False)

    def update(fraction: float) -> None:
        bar.n = round(100.0 * fraction, 1)
        bar.refresh()

    return update, bar.close


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
    what: str = "",
) -> str:
    """Run Radiance program ``name`` with ``args`` in ``cwd``; returns its stderr text or raises RadianceError.

    ``stdin``/``stdout`` are files (in ``cwd``) the program reads from and
    writes to, so no pipe can fill up; stderr is read by a thread that reports
    progress (``progress``: False, None for a bar on a terminal, True, or a
    callable taking the finished fraction).  ``timeout`` in seconds (None: no
    limit); on expiry the program is killed and the message names ``total``
    (the whole job's timeout this program had a share of) or ``timeout``.
    ``what`` says what was running (for messages).
    """
    exe = program(name)
    update, close = _bar(progress, name)
    folder = Path(cwd)
    with (
        open(folder / stdin, "rb") if stdin is not None else open(os.devnull, "rb") as fin,
        open(folder / stdout, "wb") if stdout is not None else open(os.devnull, "wb") as fout,
    ):
        try:
            proc = subprocess.Popen(
                [str(exe), *args], cwd=folder, stdin=fin, stdout=fout, stderr=subprocess.PIPE, env=environment()
            )
        except OSError as exc:
            close()
            raise RadianceError(f"Radiance: cannot start {exe}: {exc}; {INSTALL}") from None
        chunks: list[bytes] = []
        failures: list[BaseException] = []

        def read() -> None:
            assert proc.stderr is not None
            pending = b""
            while True:  # drain everything so the program never blocks on a full pipe
                data = proc.stderr.read1(4096)
                if not data:
                    break
                chunks.append(data)
                pending = (pending + data)[-512:]
                found = _PROGRESS.findall(pending)
                if found and not failures:
                    try:
                        update(min(float(found[-1]) / 100.0, 1.0))
                    except BaseException as exc:  # noqa: BLE001 - handed to the calling thread
                        failures.append(exc)
                        proc.kill()  # the caller's progress handler failed: stop

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            reader.join(5)
            close()
            label = f"{name} ({what})" if what else name
            raise RadianceError(
                f"Radiance: {label} took longer than the timeout of {total or timeout:g} s and was stopped; "
                "pass a larger timeout=, a smaller size or cheaper om.radiance.Options (lower ab)",
                b"".join(chunks).decode("latin-1"),
            ) from None
        except BaseException:
            proc.kill()
            proc.wait()
            reader.join(5)
            close()
            raise
        reader.join(5)
    if failures:
        close()
        raise failures[0]
    if proc.returncode == 0 and progress is not False:
        update(1.0)
    close()
    output = b"".join(chunks).decode("latin-1")
    if proc.returncode != 0:
        lines = error_lines(output) or [output[-2000:].strip() or "(no message)"]
        detail = "\n  ".join(lines)
        raise RadianceError(
            f"Radiance: {name}{' (' + what + ')' if what else ''} failed (exit status {proc.returncode}):\n  {detail}",
            output,
        )
    return output
