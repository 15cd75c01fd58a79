"""Running the ``povray`` program: no shell, a timeout, progress, POV-Ray's own error lines.

POV-Ray reports progress as ``Rendered 1024 of 76800 pixels (1%)`` lines on
stderr (separated by carriage returns); :func:`omnirender.process.run_watched`
turns them into a progress bar (tqdm on a terminal) and collects the rest, from
which the ``Parse Error`` / ``Fatal error`` lines are extracted when POV-Ray fails.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Any

from ..core import OmnirenderError
from ..process import ProgramTimeout, killed_by, progress_reporter, run_watched

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
    update, close = progress_reporter(progress, total_pixels, "px", "POV-Ray")
    env = dict(os.environ)
    # POV-Ray's configuration grants reading %HOME%: point it at the (temporary) working folder so a
    # scene cannot read the user's files through it (nor pick up a user povray.conf).
    env["HOME"] = str(cwd)

    def watch(tail: bytes) -> None:
        found = _PROGRESS.findall(tail.decode("latin-1"))
        if found:
            done, total = found[-1]
            update(int(done), int(total))

    try:
        returncode, raw = run_watched([exe, *args], cwd, env=env, timeout=timeout, watch=watch)
    except OSError as exc:
        raise POVRayError(f"POV-Ray: cannot start {exe}: {exc}; {_INSTALL}") from None
    except ProgramTimeout as exc:
        raise POVRayError(
            f"POV-Ray: rendering took longer than the timeout of {timeout:g} s and was stopped; "
            "pass a larger timeout=, a smaller size or a lower quality",
            exc.output.decode("latin-1"),
        ) from None
    finally:
        close()
    output = raw.decode("latin-1")
    signal = killed_by(returncode)
    if signal is not None:  # its console output holds no error of its own (configuration notes at most)
        raise POVRayError(f"POV-Ray was {signal}", output)
    if returncode != 0:
        lines = error_lines(output)
        detail = "\n  ".join(lines) if lines else output[-2000:]
        raise POVRayError(f"POV-Ray failed (exit status {returncode}):\n  {detail}", output)
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
