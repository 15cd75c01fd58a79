"""Progress of long work: a tqdm bar on a terminal, periodic ``logging`` lines otherwise.

Frame rendering, the offline engines (POV-Ray, Radiance, Mitsuba) and the demo
report progress through :class:`Progress`.  Where stderr is a terminal it draws a
tqdm bar; elsewhere (a log file, CI, a notebook's captured output) a bar would be
one unreadable line, so it logs a line on the ``"omnirender"`` logger at INFO
every :data:`LOG_INTERVAL` seconds (``mitsuba: 24/64 spp (38%), 12 s, about 20 s
left``) and one when the work is done, if it ran that long.  Like any library,
omnirender leaves the logging configuration to the application
(``logging.basicConfig(level=logging.INFO)`` shows the lines); the ``omnirender``
command shows them on stderr when stderr is not a terminal.  This module imports
only the standard library (tqdm lazily).
"""

from __future__ import annotations

import logging
import sys
import time
from typing import Any

__all__ = ["Progress", "LOG_INTERVAL", "logger", "wants_progress", "show_progress_lines"]

#: The logger progress lines go to.
logger = logging.getLogger("omnirender")
#: Seconds between two progress lines in the log.
LOG_INTERVAL = 10.0


class _StderrHandler(logging.StreamHandler):
    """Log lines to whatever ``sys.stderr`` is when they are written (tests and notebooks replace it)."""

    @property  # type: ignore[override]
    def stream(self) -> Any:
        return sys.stderr

    @stream.setter
    def stream(self, value: Any) -> None:
        pass


def show_progress_lines() -> None:
    """For applications (the ``omnirender`` command, the examples): where stderr is no terminal, print the
    progress lines there (``omnirender: ...``).  Does nothing on a terminal (the bars show) or when the
    ``omnirender`` logger is configured already."""
    if sys.stderr.isatty() or logger.handlers or logger.level != logging.NOTSET:
        return
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("omnirender: %(message)s"))
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)


def wants_progress(show: Any) -> bool:
    """Whether a ``progress=`` value asks for any report: a bar (on a terminal) or log lines (INFO enabled)."""
    if show is None:
        return sys.stderr.isatty() or logger.isEnabledFor(logging.INFO)
    return bool(show)


class Progress:
    """Progress of ``total`` steps of ``unit``, labelled ``label``.

    ``show``: None (default) a bar on a terminal, log lines elsewhere; True a bar; False nothing;
    ``"log"`` log lines (every ``interval`` seconds, default :data:`LOG_INTERVAL`).  Use
    :meth:`update` (steps done so far) or :meth:`advance`, then :meth:`close` (or a ``with`` block).
    """

    def __init__(self, total: int, label: str, unit: str = "it", show: Any = None, interval: float | None = None):
        self.total = int(total)
        self.label = label
        self.unit = unit
        self.done = 0
        self.interval = float(LOG_INTERVAL if interval is None else interval)
        self.start = time.monotonic()
        self._next_log = self.start + self.interval
        self._logged = False
        self._postfix = ""
        self._bar: Any = None
        if show is None:
            show = True if sys.stderr.isatty() else "log"
        self.mode = "log" if show == "log" else ("bar" if show else "off")
        if self.mode == "bar":
            try:
                from tqdm import tqdm
            except ImportError:  # pragma: no cover - tqdm comes with every rendering extra
                self.mode = "log"
            else:
                self._bar = tqdm(total=self.total, unit=unit, desc=label, leave=False, file=sys.stderr)

    def update(self, done: int, total: int | None = None) -> None:
        """``done`` steps of ``total`` (default: the total given at the start) are finished."""
        if total is not None:
            self.total = int(total)
        self.done = int(done)
        if self._bar is not None:
            self._bar.total = self.total
            self._bar.n = self.done
            self._bar.refresh()
        elif self.mode == "log":
            now = time.monotonic()
            if now >= self._next_log and self.done < self.total:
                self._next_log = now + self.interval
                self._log(now)

    def advance(self, n: int = 1) -> None:
        """``n`` more steps are finished."""
        self.update(self.done + n)

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        """A short note after the count (tqdm's name: the frame renderer reports failures with it)."""
        self._postfix = text
        if self._bar is not None:
            self._bar.set_postfix_str(text, refresh=refresh)

    def _log(self, now: float) -> None:
        elapsed = now - self.start
        part = f"{self.done}/{self.total} {self.unit}"
        if self.total > 0:
            part += f" ({100.0 * self.done / self.total:.0f}%)"
        left = ""
        if 0 < self.done < self.total:
            left = f", about {elapsed * (self.total - self.done) / self.done:.0f} s left"
        note = f" [{self._postfix}]" if self._postfix else ""
        logger.info("%s: %s, %.0f s%s%s", self.label, part, elapsed, left, note)
        self._logged = True

    def close(self) -> None:
        """Finish: the bar goes away; in the log, a last line if the work ran longer than the interval."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        elif self.mode == "log" and (self._logged or time.monotonic() - self.start >= self.interval):
            elapsed = time.monotonic() - self.start
            note = f" [{self._postfix}]" if self._postfix else ""
            logger.info("%s: %d/%d %s done in %.1f s%s", self.label, self.done, self.total, self.unit, elapsed, note)
        self.mode = "off"

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
