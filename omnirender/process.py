"""Running external programs (POV-Ray, Radiance): no shell, a timeout, their output watched for progress.

:func:`run_watched` starts a program, lets a thread read its console output
(so it never blocks on a full pipe) and hand the recent tail to a ``watch``
function that reports progress; an exception in ``watch`` stops the program
and reaches the caller, a timeout kills it (:class:`ProgramTimeout`).
:func:`progress_reporter` turns the ``progress=`` argument of the render
functions (None: a tqdm bar on a terminal, True/False, or a callable
``(done, total)``) into an update function.  Adapters wrap both with their own
messages; this module imports only the standard library (tqdm lazily).
"""

from __future__ import annotations

import os
import subprocess
import threading
from collections.abc import Callable, Sequence
from typing import IO, Any

__all__ = ["ProgramTimeout", "run_watched", "progress_reporter", "killed_by", "exit_description"]

#: How much of the latest output ``watch`` sees (progress lines are short).
TAIL = 512


class ProgramTimeout(Exception):
    """The program ran longer than its timeout and was killed; ``output`` is what it printed."""

    def __init__(self, output: bytes) -> None:
        super().__init__("timeout")
        self.output = output


def run_watched(
    argv: Sequence[str],
    cwd: str | os.PathLike[str],
    *,
    env: dict[str, str] | None = None,
    stdin: IO[bytes] | None = None,
    stdout: IO[bytes] | None = None,
    timeout: float | None = None,
    watch: Callable[[bytes], None] | None = None,
) -> tuple[int, bytes]:
    """Run ``argv`` in ``cwd``; returns (exit status, console output).

    The console output is stderr, or stdout and stderr together when
    ``stdout`` is None; otherwise stdout goes to the given file.  ``stdin``
    is a file (default: nothing).  OSError when the program cannot start.
    """
    proc = subprocess.Popen(
        list(argv),
        cwd=cwd,
        stdin=stdin if stdin is not None else subprocess.DEVNULL,
        stdout=stdout if stdout is not None else subprocess.PIPE,
        stderr=subprocess.PIPE if stdout is not None else subprocess.STDOUT,
        env=env,
    )
    stream = proc.stderr if stdout is not None else proc.stdout
    chunks: list[bytes] = []
    failures: list[BaseException] = []

    def read() -> None:
        assert stream is not None
        pending = b""
        while True:  # drain everything, even after a failure, so the program never blocks
            data = stream.read1(4096) if hasattr(stream, "read1") else stream.read(4096)
            if not data:
                break
            chunks.append(data)
            pending = (pending + data)[-TAIL:]
            if watch is not None and not failures:
                try:
                    watch(pending)
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
        raise ProgramTimeout(b"".join(chunks)) from None
    except BaseException:
        proc.kill()
        proc.wait()
        reader.join(5)
        raise
    finally:
        reader.join(5)
        if not reader.is_alive():  # the pipe is ours to close (else the reader still holds it)
            assert stream is not None
            stream.close()
    if failures:
        raise failures[0]
    return proc.returncode, b"".join(chunks)


#: What a signal that ended a program usually means.
_SIGNAL_HINTS = {
    "SIGKILL": "usually the system's out-of-memory killer: render a smaller image or a simpler scene",
    "SIGSEGV": "the program crashed",
    "SIGABRT": "the program aborted",
    "SIGTERM": "it was asked to stop",
    "SIGINT": "it was interrupted",
    "SIGXCPU": "it ran out of its CPU-time limit",
}


def killed_by(returncode: int) -> str | None:
    """``"killed by signal 9 (SIGKILL: ...)"`` when ``returncode`` says a signal ended the program, else None."""
    if returncode >= 0:
        return None
    import signal

    number = -returncode
    try:
        name = signal.Signals(number).name
    except ValueError:
        return f"killed by signal {number}"
    hint = _SIGNAL_HINTS.get(name)
    return f"killed by signal {number} ({name}{': ' + hint if hint else ''})"


def exit_description(returncode: int) -> str:
    """``"exit status 2"`` or ``"killed by signal 9 (SIGKILL: ...)"``."""
    return killed_by(returncode) or f"exit status {returncode}"


def progress_reporter(
    progress: Any, total: int, unit: str, label: str
) -> tuple[Callable[[int, int], None], Callable[[], None]]:
    """(update(done, total), close()) for a ``progress=`` argument: None (a bar on a terminal, log lines
    elsewhere: see :mod:`omnirender.progress`), True (a bar), False, or a callable ``(done, total)``."""
    if callable(progress):
        return progress, lambda: None
    if progress is False:
        return (lambda done, total: None), lambda: None
    from .progress import Progress

    bar = Progress(total, label, unit, show=progress)
    return bar.update, bar.close
