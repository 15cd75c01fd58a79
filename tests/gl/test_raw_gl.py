"""Raw GL calls (the entry points moderngl lacks) have the foreign-function types the GL headers declare.

ctypes reads a result as a C ``int`` unless told otherwise.  GLboolean is one byte: a driver that
leaves other bits in the register's upper bytes (NVIDIA's returned ``-962556927`` for GL_TRUE) makes
an undeclared boolean query read garbage.  The fake library below returns exactly that.
"""

from __future__ import annotations

import ctypes
import re
from pathlib import Path

import pytest

from omnirender.gl.engine import context as glcontext
from omnirender.gl.engine.context import SIGNATURES, RawGL

ROOT = Path(__file__).resolve().parents[2]
#: GL_TRUE / GL_FALSE with garbage in the upper bytes, as NVIDIA's driver leaves them (0xC6A08C01 = -962556927)
_DIRTY = 0xC6A08C00


class _FakeLibGL:
    """A libOpenGL whose boolean queries return the argument's low bit under garbage upper bytes."""

    def __init__(self) -> None:
        self._keep: list = []

    def __getattr__(self, name: str):
        if not name.startswith("gl"):
            raise AttributeError(name)
        if name.startswith("glIs"):
            callback = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_uint)(lambda value: _DIRTY | (value & 1))
        else:
            callback = ctypes.CFUNCTYPE(None)(lambda: None)
        self._keep.append(callback)
        fn = ctypes.cast(callback, ctypes.CFUNCTYPE(ctypes.c_int))  # a foreign function with ctypes' defaults
        setattr(self, name, fn)
        return fn


def test_gl_booleans_are_read_as_one_byte(monkeypatch):
    monkeypatch.setattr(RawGL, "_lib", _FakeLibGL())
    raw = RawGL()
    for name in ("glIsRenderbuffer", "glIsFramebuffer", "glIsTexture", "glIsEnabled"):
        fn = getattr(raw, name)
        assert (fn(7), fn(8)) == (1, 0), f"{name} read {fn(7)} / {fn(8)} instead of GL_TRUE / GL_FALSE"


def test_every_raw_call_is_declared():
    """Each raw GL call (``raw.gl*``, ``gl.gl*``) in the package and the tests names an entry of SIGNATURES."""
    used: dict[str, set[str]] = {}
    pattern = re.compile(r"\b(?:raw|gl|_gl\(\))\.(gl[A-Z]\w*)")
    for folder in ("omnirender", "tests", "bench"):
        for path in (ROOT / folder).rglob("*.py"):
            for name in pattern.findall(path.read_text(encoding="utf-8")):
                used.setdefault(name, set()).add(str(path.relative_to(ROOT)))
    assert used, "no raw GL calls found: the pattern is out of date"
    missing = {name: sorted(where) for name, where in used.items() if name not in SIGNATURES}
    assert not missing, f"raw GL calls without a declared signature: {missing}"


def test_the_raw_library_is_reached_only_through_declared_entry_points():
    offenders = []
    for folder in ("omnirender", "tests", "bench"):
        for path in (ROOT / folder).rglob("*.py"):
            if path == Path(glcontext.__file__).resolve():
                continue
            if re.search(r"\._lib\.gl\w+", path.read_text(encoding="utf-8")):
                offenders.append(str(path.relative_to(ROOT)))
    assert not offenders, f"raw GL entry points taken from the library without their signature: {offenders}"


@pytest.mark.parametrize("name", sorted(SIGNATURES))
def test_signatures_use_the_gl_header_types(name):
    args, result = SIGNATURES[name]
    allowed = {ctypes.c_uint, ctypes.c_int, ctypes.c_float, ctypes.c_double, ctypes.c_ubyte, ctypes.c_void_p}
    for arg in args:
        assert arg in allowed or issubclass(arg, ctypes._Pointer), f"{name}: argument type {arg}"
    if name.startswith("glIs"):
        assert result is ctypes.c_ubyte, f"{name} returns a GLboolean (one byte)"
    elif name == "glCheckFramebufferStatus":
        assert result is ctypes.c_uint, f"{name} returns a GLenum"
    else:
        assert result is None, f"{name} returns void"
