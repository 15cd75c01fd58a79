"""Formatting of Radiance scene descriptions (``.rad``).

A Radiance primitive is ``modifier type identifier``, then the count and the
string arguments, ``0`` (integer arguments), and the count and the real
arguments.  Radiance splits arguments at white space, runs every line that
starts with ``!`` as a shell command and skips lines starting with ``#``, so
the rules that keep a scene from injecting anything live here: numbers must be
finite; identifiers are generated (``om<n>``) and checked; string arguments
(function names, expressions, file names) come from a small alphabet without
white space, quotes, ``!`` or ``#``; free text (node names) only appears in
comments after reduction to a safe alphabet.  Every generated line starts
with a count, an identifier or ``#``, never with user text.  Large arrays
(polygons, cylinders, OBJ files) are formatted with one ``%``-operation each.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

__all__ = [
    "RadError",
    "number",
    "numbers",
    "token",
    "identifier",
    "comment",
    "primitive",
    "rows_text",
    "defined_names",
]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")
#: Characters allowed in string arguments: names, numbers, calcomp expressions, relative file names.
_TOKEN = re.compile(r"[A-Za-z0-9_.+\-*/^(),:;=<>|&]+\Z")
_SAFE_COMMENT = re.compile(r"[^A-Za-z0-9_./\- ]")
#: Longest string argument accepted (Radiance's own limit is larger; this keeps messages readable).
MAX_TOKEN = 512


class RadError(ValueError):
    """A value cannot be written to a Radiance scene description (non-finite number, unsafe text)."""


def number(value: Any, owner: str = "Radiance") -> str:
    """A finite number (``%.9g``); booleans become 1/0."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise RadError(f"{owner}: {value!r} is not a number") from None
    if not math.isfinite(v):
        raise RadError(f"{owner}: cannot write the non-finite number {value!r} to a Radiance scene")
    if v == 0.0:
        return "0"
    return f"{v:.9g}"


def numbers(values: Iterable[Any], owner: str = "Radiance") -> str:
    """Space-separated finite numbers."""
    return " ".join(number(v, owner) for v in values)


def token(value: Any, owner: str = "Radiance", what: str = "string argument") -> str:
    """``value`` if it is a safe string argument, else RadError.

    No white space, quotes, ``!`` or ``#``; and, as string arguments may be
    file names Radiance opens, no absolute paths and no ``..``: files are found
    in the scene's folder and on ``RAYPATH`` only.
    """
    if not isinstance(value, str) or not value or len(value) > MAX_TOKEN or not _TOKEN.match(value):
        raise RadError(
            f"{owner}: {what} {value!r:.80} cannot be written to a Radiance scene: use letters, digits and "
            f"_ . + - * / ^ ( ) , : ; = < > | & only (no spaces, quotes, '!' or '#'), at most {MAX_TOKEN} characters"
        )
    if value.startswith("/") or ".." in value:
        raise RadError(
            f"{owner}: {what} {value!r:.80} names a file outside the scene's folder; give a file name relative to "
            "it (or on RAYPATH), without '/' at the start or '..'"
        )
    return value


def identifier(value: Any, owner: str = "Radiance") -> str:
    """``value`` if it is a plain identifier (a letter or ``_`` first, then letters, digits, ``_ . -``)."""
    if not isinstance(value, str) or len(value) > MAX_TOKEN or not _IDENT.match(value):
        raise RadError(
            f"{owner}: {value!r:.80} is not a valid Radiance name (a letter or '_' first, then letters, digits, "
            "'_', '.' or '-')"
        )
    return value


def comment(text: str) -> str:
    """A one-line ``#`` comment: characters outside a safe alphabet become ``_``."""
    return "# " + _SAFE_COMMENT.sub("_", str(text))[:200]


def primitive(
    modifier: str,
    kind: str,
    ident: str,
    strings: Sequence[str] = (),
    reals: Sequence[Any] | str = (),
    owner: str = "Radiance",
    *,
    real_count: int | None = None,
) -> str:
    """One primitive: ``modifier kind ident`` and its argument lines.

    ``strings`` are checked with :func:`token`; ``reals`` are numbers, or an
    already formatted text (from :func:`rows_text`) with ``real_count`` values.
    """
    head = f"{identifier(modifier, owner)} {identifier(kind, owner)} {identifier(ident, owner)}\n"
    args = " ".join(token(s, owner) for s in strings)
    line1 = f"{len(strings)} {args}\n" if strings else "0\n"
    if isinstance(reals, str):
        assert real_count is not None
        line3 = f"{real_count}\n{reals}"
    else:
        values = list(reals)
        line3 = f"{len(values)} {numbers(values, owner)}\n" if values else "0\n"
    return head + line1 + "0\n" + line3


def rows_text(array: np.ndarray, owner: str = "Radiance", what: str = "coordinates", fmt: str = "%.9g") -> str:
    """One line of space-separated numbers per row of a float array, in one formatting pass."""
    array = np.asarray(array, dtype=np.float64)
    if array.size and not np.all(np.isfinite(array)):
        raise RadError(f"{owner}: {what} contain non-finite values")
    if array.ndim == 1:
        array = array[None, :]
    n, k = array.shape
    if n == 0:
        return ""
    line = "\t" + " ".join([fmt] * k) + "\n"
    return (line * n) % tuple(array.ravel().tolist())


def defined_names(text: str) -> list[str]:
    """The identifiers that primitives in Radiance ``text`` define (best effort: stops at anything unusual).

    Used to name the node whose ``om.radiance.Raw`` text Radiance complains about.
    """
    words: list[str] = []
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith(("#", "!")):
            continue
        words += stripped.split()
    names, i = [], 0
    try:
        while i + 2 < len(words):
            names.append(words[i + 2])
            if words[i + 1] == "alias":
                i += 4
                continue
            i += 3
            for _ in range(3):  # string, integer and real arguments, each preceded by its count
                i += int(words[i]) + 1
    except (ValueError, IndexError):
        pass
    return names
