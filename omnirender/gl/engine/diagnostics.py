"""GLSL compiler diagnostics of every driver, parsed into one record type.

Drivers write their info logs in their own formats (all documented by the vendors):

* Mesa (llvmpipe, softpipe, radeonsi, iris, nouveau, ... on Linux)::

      0:43003(12): error: `undefined_name' undeclared

  ``source:line(column): severity: message``;
* NVIDIA (Linux and Windows)::

      0(43003) : error C1503: undefined variable "undefined_name"

  ``source(line) : severity Cnnnn: message``;
* AMD (Windows and AMDGPU-PRO), Intel (Windows), Apple and other compilers derived from the
  3Dlabs/Khronos reference front end::

      ERROR: 0:43003: 'undefined_name' : undeclared identifier

  ``SEVERITY: source:line: message`` (plus summary lines such as ``ERROR: 1 compilation errors.``).

:func:`parse` turns a log (or moderngl's exception text, which names the stage above each log) into
:class:`Diagnostic` records: severity, source-string number, line, column, vendor code, message and
the shader stage.  The line is the one the compiler reports, i.e. after ``#line`` directives; callers
that encode a meaning into ``#line`` numbers (the deferred pipeline encodes model and stage) decode it
from :attr:`Diagnostic.line`.  Lines in no known format are kept as location-less diagnostics of the
severity they name (or ``"error"``), so no message is ever lost.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["Diagnostic", "parse", "errors"]

#: moderngl's headings above each stage's log ("fragment_shader\n===============").
_STAGES = (
    "vertex_shader",
    "fragment_shader",
    "geometry_shader",
    "tess_control_shader",
    "tess_evaluation_shader",
    "compute_shader",
)

# Mesa: "0:12(7): error: message" (the column may be absent: "0:12: error: ...")
_MESA = re.compile(
    r"^\s*(?P<source>\d+):(?P<line>\d+)(?:\((?P<column>\d+)\))?\s*:\s*"
    r"(?P<severity>(?:preprocessor )?error|warning|info|note)\s*:\s*(?P<message>.*)$",
    re.IGNORECASE,
)
# NVIDIA: "0(12) : error C1503: message" (the code may be absent in some driver versions)
_NVIDIA = re.compile(
    r"^\s*(?P<source>\d+)\((?P<line>\d+)\)\s*:\s*(?P<severity>(?:fatal |internal )?error|warning|note)"
    r"(?:\s+(?P<code>[A-Z]\d{4}))?\s*:\s*(?P<message>.*)$",
    re.IGNORECASE,
)
# 3Dlabs/Khronos front ends (AMD, Intel on Windows, Apple, ANGLE): "ERROR: 0:12: message"
_REFERENCE = re.compile(
    r"^\s*(?P<severity>ERROR|WARNING|INFO)\s*:\s*(?P<source>\d+):(?P<line>\d+):\s*(?P<message>.*)$",
    re.IGNORECASE,
)
# anything else that names a severity: "ERROR: 1 compilation errors.", "error: linking failed"
_BARE = re.compile(r"^\s*(?P<severity>(?:fatal )?error|warning)\b\s*:?\s*(?P<message>.*)$", re.IGNORECASE)
_SUMMARY = re.compile(r"^\d+ compilation errors?\.|^compilation terminated|^no code generated", re.IGNORECASE)


@dataclass(frozen=True)
class Diagnostic:
    """One compiler message: where it points (source string, line, column) and what it says.

    ``severity`` is ``"error"``, ``"warning"`` or ``"info"``; ``source``, ``line`` and ``column`` are
    None when the driver gives no location; ``code`` is the vendor's message code (NVIDIA's
    ``C1503``) or None; ``stage`` is moderngl's stage name (``"fragment_shader"``) when known;
    ``text`` is the line as the driver wrote it.
    """

    severity: str
    message: str
    source: int | None = None
    line: int | None = None
    column: int | None = None
    code: str | None = None
    stage: str | None = None
    text: str = ""

    @property
    def located(self) -> bool:
        """Whether the diagnostic names a line."""
        return self.line is not None


def _severity(word: str) -> str:
    word = word.lower()
    if "error" in word:
        return "error"
    if "warning" in word:
        return "warning"
    return "info"


def parse(log: str) -> list[Diagnostic]:
    """The diagnostics in a driver's info log (Mesa, NVIDIA, AMD, Intel or Apple format), in order.

    ``log`` may be moderngl's exception text, whose stage headings (``fragment_shader`` over a line
    of ``=``) set :attr:`Diagnostic.stage` of the messages below them.  Summary lines that only
    count errors (``ERROR: 1 compilation errors.  No code generated.``) are left out.
    """
    found: list[Diagnostic] = []
    stage: str | None = None
    for raw in str(log).splitlines():
        text = raw.strip()
        if not text or set(text) == {"="}:
            continue
        if text in _STAGES:
            stage = text
            continue
        match = _MESA.match(text)
        if match is not None:
            found.append(
                Diagnostic(
                    _severity(match["severity"]),
                    match["message"].strip(),
                    int(match["source"]),
                    int(match["line"]),
                    int(match["column"]) if match["column"] else None,
                    None,
                    stage,
                    text,
                )
            )
            continue
        match = _NVIDIA.match(text)
        if match is not None:
            found.append(
                Diagnostic(
                    _severity(match["severity"]),
                    match["message"].strip(),
                    int(match["source"]),
                    int(match["line"]),
                    None,
                    match["code"],
                    stage,
                    text,
                )
            )
            continue
        match = _REFERENCE.match(text)
        if match is not None:
            found.append(
                Diagnostic(
                    _severity(match["severity"]),
                    match["message"].strip(),
                    int(match["source"]),
                    int(match["line"]),
                    None,
                    None,
                    stage,
                    text,
                )
            )
            continue
        match = _BARE.match(text)
        if match is not None:
            message = match["message"].strip()
            if not _SUMMARY.match(message):
                found.append(Diagnostic(_severity(match["severity"]), message, stage=stage, text=text))
    return found


def errors(log: str) -> list[Diagnostic]:
    """The error diagnostics of ``log`` (warnings and notes left out)."""
    return [d for d in parse(log) if d.severity == "error"]
