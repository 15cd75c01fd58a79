"""Running the ``povray`` program: no shell, a timeout, progress, POV-Ray's own error lines.

POV-Ray reports progress as ``Rendered 1024 of 76800 pixels (1%)`` lines on
stderr (separated by carriage returns); a reader thread turns them into a
progress bar (tqdm on a terminal) and collects the rest, from which the
``Parse Error`` / ``Fatal error`` lines are extracted when POV-Ray fails.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..core import OmnirenderError

__all__ = ["POVRayError", "find_povray", "run_povray", "error_lines"]

_PROGRESS = re.compile(r"Rendered (\d+) of (\d+) pixels")
_INSTALL = "install it with `apt-get install povray` (Debian/Ubuntu) or from https://www.povray.org"


class POVRayError(OmnirenderError, RuntimeError):
    """POV-Ray is missing, failed or timed out; the message carries POV-Ray's own error lines."""

    def __init__(self, message: str, output: str = "") -> None:
        super().__init__(message)
        self.output = output


def find_povray() -> str | None:
    """The path of the ``povray`` program, or None."""
    return shutil.which("povray")


def error_lines(output: str) -> list[str]:
    """POV-Ray's error report: from the first ``File '...' line N:`` / error line to the end, unwrapped."""
    lines = output.replace("\r", "\n").split("\n")
    start = None
    for i, line in enumerate(lines):
        if re.match(r"\s*File '.*' line \d+:", line) or re.search(
            r"(Parse Error|Fatal error|Possible Parse Error)", line
        ):
            start = i
            break
    if start is None:
        interesting = [ln for ln in lines if re.search(r"(?i)error|failed|cannot|unable", ln)]
        return [ln.strip() for ln in interesting][-10:]
    out: list[str] = []
    for line in lines[start:]:
        if not line.strip() or line.startswith("====") or _PROGRESS.search(line):
            continue
        if line.startswith(" ") and out and not re.match(r"\s*File '", line):
            out[-1] += line  # POV-Ray wraps long messages at 80 columns with a leading space
        else:
            out.append(line.strip())
    return out[:20]


def _bar(progress: Any, total_hint: int) -> tuple[Callable[[int, int], None], Callable[[], None]]:
    """(update(done, total), close()) for ``progress``: None (tqdm on a terminal), bool, or a callable."""
    if callable(progress):
        return progress, lambda: None
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress:
        return (lambda done, total: None), lambda: None
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is in the 'all' extra
        return (lambda done, total: None), lambda: None
    bar = tqdm(total=total_hint, unit="px", desc="POV-Ray", leave=False)

    def update(done: int, total: int) -> None:
        bar.total = total
        bar.n = done
        bar.refresh()

    return update, bar.close


def run_povray(
    args: list[str],
    cwd: str | os.PathLike[str],
    *,
    timeout: float | None = 600.0,
    progress: Any = None,
    total_pixels: int = 0,
) -> str:
    """Run povray with ``args`` in ``cwd``; returns its console output or raises POVRayError."""
    exe = find_povray()
    if exe is None:
        raise POVRayError(f"POV-Ray: the povray program was not found on PATH; {_INSTALL}")
    update, close = _bar(progress, total_pixels)
    env = dict(os.environ)
    # POV-Ray's configuration grants reading %HOME%: point it at the (temporary) working folder so a
    # scene cannot read the user's files through it (nor pick up a user povray.conf).
    env["HOME"] = str(cwd)
    try:
        proc = subprocess.Popen(
            [exe, *args],
            cwd=cwd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env=env,
        )
    except OSError as exc:
        close()
        raise POVRayError(f"POV-Ray: cannot start {exe}: {exc}; {_INSTALL}") from None
    chunks: list[bytes] = []
    failures: list[BaseException] = []  # an exception of the progress callback, re-raised in this thread

    def read() -> None:
        assert proc.stdout is not None
        pending = b""
        while True:  # drain everything, even after a failure, so POV-Ray never blocks on a full pipe
            data = proc.stdout.read1(4096) if hasattr(proc.stdout, "read1") else proc.stdout.read(4096)
            if not data:
                break
            chunks.append(data)
            pending = (pending + data)[-256:]
            found = _PROGRESS.findall(pending.decode("latin-1"))
            if found and not failures:
                done, total = found[-1]
                try:
                    update(int(done), int(total))
                except BaseException as exc:  # noqa: BLE001 - handed to the main thread
                    failures.append(exc)
                    proc.kill()  # the caller's progress handler failed: stop rendering

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        reader.join(5)
        close()
        raise POVRayError(
            f"POV-Ray: rendering took longer than the timeout of {timeout:g} s and was stopped; "
            "pass a larger timeout=, a smaller size or a lower quality",
            b"".join(chunks).decode("latin-1"),
        ) from None
    except BaseException:
        proc.kill()
        proc.wait()
        reader.join(5)
        close()
        raise
    reader.join(5)
    close()
    if failures:
        raise failures[0]
    output = b"".join(chunks).decode("latin-1")
    if proc.returncode != 0:
        lines = error_lines(output)
        detail = "\n  ".join(lines) if lines else output[-2000:]
        raise POVRayError(f"POV-Ray failed (exit status {proc.returncode}):\n  {detail}", output)
    return output


def read_png(path: Path) -> Any:
    """The (H, W, 4) uint8 RGBA array of a PNG written by POV-Ray."""
    import numpy as np
    from PIL import Image as PILImage

    with PILImage.open(path) as img:
        return np.asarray(img.convert("RGBA"), dtype=np.uint8)


def read_ppm(path: Path) -> Any:
    """The (H, W, 3) array of a binary PPM (uint16 for 16-bit files; Pillow would drop to 8 bits)."""
    import numpy as np

    data = Path(path).read_bytes()
    token = re.compile(rb"\s*(#[^\n]*\n|\S+)")
    pos, fields = 0, []
    while len(fields) < 4:
        m = token.match(data, pos)
        if m is None:
            raise POVRayError(f"POV-Ray wrote a malformed PPM file {path}")
        pos = m.end()
        if not m.group(1).startswith(b"#"):
            fields.append(m.group(1))
    if fields[0] != b"P6":
        raise POVRayError(f"POV-Ray wrote {fields[0]!r} instead of a binary PPM in {path}")
    w, h, maxval = (int(v) for v in fields[1:])
    dtype = ">u2" if maxval > 255 else "u1"
    return np.frombuffer(data, dtype, count=w * h * 3, offset=pos + 1).reshape(h, w, 3).astype(np.uint16)
