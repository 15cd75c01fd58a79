"""Formatting of POV-Ray 3.7 scene description language (SDL).

Everything that turns Python values into SDL text lives here, so the rules
that keep a scene from injecting directives are in one place: numbers must be
finite, keywords must be identifiers, free text (node names) is reduced to a
safe alphabet before it goes into a comment, and file names are accepted only
from a safe alphabet.  Large arrays (``mesh2``) are formatted with one
``%``-operation over the whole buffer, not a Python loop per vertex.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "SDLError",
    "number",
    "vector",
    "color",
    "matrix",
    "comment",
    "identifier",
    "file_name",
    "block",
    "params_text",
    "vectors_text",
    "triples_text",
]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_SAFE_COMMENT = re.compile(r"[^A-Za-z0-9_./\- ]")
_SAFE_FILE = re.compile(r"[A-Za-z0-9_./\-]+\Z")


class SDLError(ValueError):
    """A value cannot be written as POV-Ray SDL (non-finite number, unsafe name)."""


def number(value: Any, owner: str = "POV-Ray") -> str:
    """A finite number in SDL (``%.9g``); booleans become 1/0."""
    v = float(value)
    if not math.isfinite(v):
        raise SDLError(f"{owner}: cannot write the non-finite number {value!r} to SDL")
    if v == 0.0:
        return "0"
    return f"{v:.9g}"


def vector(values: Iterable[Any], owner: str = "POV-Ray") -> str:
    """``<a,b,c>`` from finite numbers."""
    return "<" + ",".join(number(v, owner) for v in values) + ">"


def color(values: Sequence[float], transmit: float = 0.0, owner: str = "POV-Ray") -> str:
    """``rgb <r,g,b>`` or ``rgbt <r,g,b,t>`` when ``transmit`` is non-zero."""
    rgb = list(values)[:3]
    if transmit:
        return "rgbt " + vector([*rgb, transmit], owner)
    return "rgb " + vector(rgb, owner)


def matrix(m: np.ndarray, owner: str = "POV-Ray") -> str:
    """``matrix <...>`` for a 4x4 column-vector matrix (POV-Ray uses row vectors).

    POV-Ray maps ``(x, y, z, 1)`` by the 4x3 matrix whose rows are the images
    of the axes and the translation, i.e. the transposed upper 3x4 block.
    """
    m = np.asarray(m, dtype=np.float64)
    values = np.concatenate([m[:3, :3].T.reshape(-1), m[:3, 3]])
    return "matrix " + vector(values, owner)


def comment(text: str) -> str:
    """A one-line ``//`` comment: characters outside a safe alphabet become ``_``."""
    return "// " + _SAFE_COMMENT.sub("_", str(text))[:200]


def identifier(name: Any, owner: str = "POV-Ray") -> str:
    """``name`` if it is a plain SDL identifier (letters, digits, ``_``), else SDLError."""
    if not isinstance(name, str) or not _IDENT.match(name):
        raise SDLError(f"{owner}: {name!r} is not a valid POV-Ray keyword (letters, digits and '_' only)")
    return name


def file_name(name: str, owner: str = "POV-Ray") -> str:
    """A quoted file name; only letters, digits and ``_ . / -`` are accepted (no quotes, no newlines)."""
    if not isinstance(name, str) or not _SAFE_FILE.match(name):
        raise SDLError(
            f"{owner}: file name {name!r} contains characters that are unsafe in POV-Ray SDL; "
            "use letters, digits, '_', '.', '/' and '-' only"
        )
    return f'"{name}"'


#: Blocks whose body starts with comma-separated arguments (``scattering { 1, <0.1,0.1,0.1> }``).
ARGUMENT_BLOCKS = frozenset({"scattering"})
#: The key of a nested block's positional arguments (see ``om.povray.Block``).
ARGS = "$args"


def _argument(value: Any, owner: str) -> str:
    if isinstance(value, str):
        return identifier(value, owner)
    if isinstance(value, (bool, int, float, np.integer, np.floating)):
        return number(value, owner)
    try:
        seq = [float(v) for v in value]
    except (TypeError, ValueError):
        raise SDLError(f"{owner}: block argument {value!r} must be a number, a vector or a keyword") from None
    return vector(seq, owner)


def _value(key: str, value: Any, owner: str) -> str | None:
    if value is None or value is False:
        return None
    if value is True:
        return key
    if isinstance(value, Mapping):
        return block(key, value, owner)
    if key in ARGUMENT_BLOCKS:
        raise SDLError(
            f"{owner}: {key} is a POV-Ray block with arguments ({key} {{ TYPE, COLOR ... }}), not a {key} value; "
            f"write it as om.povray.Block(1, (0.1, 0.1, 0.1), extinction=0.5) or use om.povray.Raw for other SDL"
        )
    if isinstance(value, str):
        # Only bare identifiers (pattern or keyword names) may appear as text.
        return f"{key} {identifier(value, owner)}"
    if isinstance(value, (int, float, np.integer, np.floating)):
        return f"{key} {number(value, owner)}"
    try:
        seq = [float(v) for v in value]
    except (TypeError, ValueError):
        raise SDLError(f"{owner}: cannot write {key}={value!r} to SDL (use numbers, vectors, bools or dicts)") from None
    return f"{key} {vector(seq, owner)}"


def params_text(params: Mapping[str, Any], owner: str = "POV-Ray") -> str:
    """Space-separated ``key value`` items: numbers, vectors, ``True`` (bare keyword), dicts (nested blocks)."""
    items = []
    for key, value in params.items():
        text = _value(identifier(key, owner), value, owner)
        if text is not None:
            items.append(text)
    return " ".join(items)


def block(name: str, params: Mapping[str, Any], owner: str = "POV-Ray") -> str:
    """``name { key value ... }``; an ``"$args"`` entry (a list) is written first, comma-separated.

    ``block("scattering", {"$args": [1, (0.1, 0.1, 0.1)], "extinction": 0.5})``
    gives ``scattering { 1, <0.1,0.1,0.1> extinction 0.5 }``.
    """
    params = dict(params)
    args = params.pop(ARGS, None)
    parts = []
    if args is not None:
        if isinstance(args, (str, Mapping)) or not hasattr(args, "__iter__"):
            raise SDLError(f"{owner}: the arguments of the {name} block must be a list, got {args!r}")
        parts.append(", ".join(_argument(a, owner) for a in args))
    rest = params_text(params, owner)
    if rest:
        parts.append(rest)
    return f"{identifier(name, owner)} {{ {' '.join(parts)} }}"


def _finite(array: np.ndarray, owner: str, what: str) -> None:
    if array.size and not np.all(np.isfinite(array)):
        raise SDLError(f"{owner}: {what} contain non-finite values")


def vectors_text(array: np.ndarray, owner: str = "POV-Ray", what: str = "vectors", fmt: str = "%.7g") -> str:
    """``<a,b,c>,\\n`` lines (or ``<u,v>``) for a whole (N, k) float array in one formatting pass."""
    array = np.asarray(array)
    _finite(array, owner, what)
    n, k = array.shape
    if n == 0:
        return ""
    line = "<" + ",".join([fmt] * k) + ">,\n"
    text = (line * n) % tuple(array.ravel().tolist())
    return text[:-2] + "\n"  # no comma after the last item


def triples_text(array: np.ndarray) -> str:
    """``<i,j,k>,\\n`` lines for an (M, 3) integer array in one formatting pass."""
    array = np.asarray(array)
    n = array.shape[0]
    if n == 0:
        return ""
    text = ("<%d,%d,%d>,\n" * n) % tuple(array.ravel().tolist())
    return text[:-2] + "\n"


def sextuples_text(array: np.ndarray) -> str:
    """``<i,j,k>,a,b,c,\\n`` lines (face indices followed by texture indices) for an (M, 6) array."""
    array = np.asarray(array)
    n = array.shape[0]
    if n == 0:
        return ""
    text = ("<%d,%d,%d>,%d,%d,%d,\n" * n) % tuple(array.ravel().tolist())
    return text[:-2] + "\n"
