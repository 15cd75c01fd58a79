"""Shared test configuration.

Tests that need an engine use the markers ``gl``, ``povray``, ``mitsuba``,
``radiance``, ``window``, ``chromium`` (web pages in headless Chromium) or
``gltf_validator`` (the Khronos validator from npm).  When
the engine is missing they are skipped, except when
``OMNIRENDER_REQUIRE_ENGINES=1`` (set by ``.ci/run``): then they fail, so CI
can never pass by skipping.

GL tests that need more than OpenGL 3.3 core without multisampling (what every conforming driver
offers, Mesa's softpipe included) declare it with ``@pytest.mark.gl_needs(samples=4)`` (multisampling
with at least that many samples) or ``@pytest.mark.gl_needs(version=400)`` (an OpenGL 4.0 context):
on a driver without it they are skipped with the reason, also in CI (a driver's capability, not a
missing engine; the softpipe and GL 4.1 jobs of ``.ci/run`` rely on it).
"""

from __future__ import annotations

import os

import pytest

REQUIRE = os.environ.get("OMNIRENDER_REQUIRE_ENGINES") == "1"


def _gl() -> tuple[bool, str]:
    try:
        import moderngl

        ctx = moderngl.create_standalone_context(backend="egl")
        ctx.release()
        return True, ""
    except Exception as exc:  # pragma: no cover - depends on the machine
        return False, f"no headless OpenGL (moderngl + EGL): {exc}"


def _povray() -> tuple[bool, str]:
    import shutil

    return (shutil.which("povray") is not None, "the povray program is not installed (apt-get install povray)")


def _mitsuba() -> tuple[bool, str]:
    try:
        import mitsuba
    except Exception as exc:  # pragma: no cover
        return False, f"mitsuba is not importable: {exc}"
    if getattr(mitsuba, "__file__", None) is None:  # a folder named mitsuba on sys.path, not the package
        return False, f"'mitsuba' is a namespace package ({list(getattr(mitsuba, '__path__', []))}), not Mitsuba 3"
    return True, ""


def _radiance() -> tuple[bool, str]:
    from omnirender.radiance import available

    return available()


def _window() -> tuple[bool, str]:
    import shutil

    ok = shutil.which("Xvfb") is not None
    try:
        import glfw  # noqa: F401
    except Exception as exc:  # pragma: no cover
        return False, f"glfw is not importable: {exc}"
    return ok, "Xvfb is not installed (apt-get install xvfb)"


def _chromium() -> tuple[bool, str]:
    return (chromium_program() is not None, "Chromium is not installed (apt-get install chromium)")


def chromium_program() -> str | None:
    """The headless browser used for the web-page tests (Debian's ``chromium``)."""
    import shutil

    return shutil.which("chromium") or shutil.which("chromium-browser")


def _validator() -> tuple[bool, str]:
    from gltf_files import gltf_validator

    return (
        gltf_validator() is not None,
        "the glTF validator is not installed (npm install --prefix tools/gltf-validator)",
    )


_CHECKS = {
    "gltf_validator": _validator,
    "gl": _gl,
    "povray": _povray,
    "mitsuba": _mitsuba,
    "radiance": _radiance,
    "window": _window,
    "chromium": _chromium,
}
_cache: dict[str, tuple[bool, str]] = {}


def engine_available(name: str) -> tuple[bool, str]:
    if name not in _cache:
        _cache[name] = _CHECKS[name]()
    return _cache[name]


_gl_caps: dict | None = None


def gl_capabilities() -> dict:
    """The headless context's renderer, version code (330, 410, 450) and most multisampling samples."""
    global _gl_caps
    if _gl_caps is None:
        import moderngl

        ctx = moderngl.create_standalone_context(backend="egl")
        try:
            _gl_caps = {
                "renderer": str(ctx.info.get("GL_RENDERER", "unknown")),
                "version": int(ctx.version_code),
                "samples": int(ctx.max_samples),
            }
        finally:
            ctx.release()
    return _gl_caps


def _gl_needs(item: pytest.Item) -> str | None:
    """Why the test's ``gl_needs`` marker cannot be met by this machine's OpenGL driver, or None."""
    marker = item.get_closest_marker("gl_needs")
    if marker is None or not engine_available("gl")[0]:
        return None
    caps = gl_capabilities()
    samples = int(marker.kwargs.get("samples", 0))
    version = int(marker.kwargs.get("version", 0))
    if samples and caps["samples"] < samples:
        return f"needs multisampling ({samples} samples); {caps['renderer']} offers {caps['samples']}"
    if version and caps["version"] < version:
        return (
            f"needs OpenGL {version // 100}.{version % 100 // 10}; {caps['renderer']} offers "
            f"{caps['version'] // 100}.{caps['version'] % 100 // 10}"
        )
    return None


def pytest_runtest_setup(item: pytest.Item) -> None:
    for name in _CHECKS:
        if item.get_closest_marker(name) is None:
            continue
        ok, why = engine_available(name)
        if not ok:
            if REQUIRE:
                pytest.fail(f"engine {name!r} is required in CI but unavailable: {why}", pytrace=False)
            pytest.skip(why)
    why = _gl_needs(item)
    if why is not None:
        pytest.skip(why)
