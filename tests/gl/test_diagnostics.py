"""GLSL compiler diagnostics of every driver (Mesa, NVIDIA, AMD, Intel, Apple) traced back to the user's code.

The sample logs are the vendors' documented formats, with the messages their compilers write for an
undeclared identifier; the line 43003 is what the deferred pipeline's ``#line`` encoding gives line 3
of the lighting stage of shading model number 3.
"""

from __future__ import annotations

import re

import pytest

import omnirender as om
from omnirender.gl.deferred.glsl import explain, first_line
from omnirender.gl.engine.diagnostics import Diagnostic, errors, parse

MESA = "0:{line}(12): error: `undefined_name' undeclared"
NVIDIA = '0({line}) : error C1503: undefined variable "undefined_name"'
AMD = "ERROR: 0:{line}: 'undefined_name' : undeclared identifier\nERROR: 1 compilation errors.  No code generated."
INTEL = "ERROR: 0:{line}: 'undefined_name' : undeclared identifier\n\n"
APPLE = "ERROR: 0:{line}: Use of undeclared identifier 'undefined_name'"
VENDORS = {"mesa": MESA, "nvidia": NVIDIA, "amd": AMD, "intel": INTEL, "apple": APPLE}


def _moderngl(log: str, stage: str = "fragment_shader") -> str:
    """The text of moderngl's exception around a driver log."""
    return f"GLSL Compiler failed\n\n{stage}\n{'=' * len(stage)}\n{log}\n"


@pytest.mark.parametrize("vendor", sorted(VENDORS))
def test_every_vendor_format_gives_line_stage_and_message(vendor):
    found = parse(_moderngl(VENDORS[vendor].format(line=43003)))
    assert len(found) == 1, found
    d = found[0]
    assert (d.severity, d.source, d.line, d.stage) == ("error", 0, 43003, "fragment_shader")
    assert "undefined_name" in d.message and d.located


def test_columns_codes_warnings_and_unlocated_messages():
    log = "\n".join(
        [
            "0:7(3): warning: `x' used uninitialized",
            "0(12) : warning C7533: global variable gl_FragColor is deprecated after version 120",
            "0(13) : error C0000: syntax error, unexpected '}', expecting ',' or ';' at token \"}\"",
            "WARNING: 0:4: 'float' : precision qualifier ignored",
            "error: linking with uncompiled/unspecialized shader",
        ]
    )
    found = parse(log)
    assert [(d.severity, d.line, d.column, d.code) for d in found] == [
        ("warning", 7, 3, None),
        ("warning", 12, None, "C7533"),
        ("error", 13, None, "C0000"),
        ("warning", 4, None, None),
        ("error", None, None, None),
    ]
    assert not found[-1].located and found[-1].message.startswith("linking with uncompiled")
    assert [d.line for d in errors(log)] == [13, None]


def test_stage_headings_follow_moderngls_layout():
    text = _moderngl(MESA.format(line=5), "vertex_shader") + _moderngl(NVIDIA.format(line=9))
    assert [(d.stage, d.line) for d in parse(text)] == [("vertex_shader", 5), ("fragment_shader", 9)]
    assert isinstance(parse(text)[0], Diagnostic)


def _broken() -> om.gl.ShadingModel:
    return om.gl.ShadingModel(
        "broken",
        gbuffer={"color": "color"},
        lbuffer={"light": "float"},
        lighting="void lighting(Pixel p, GBuffer g, Light light, inout LBuffer l) {\n"
        "    l.light += dot(p.N, light.L);\n    l.light += undefined_name;\n}",
        shading="vec3 shading(Pixel p, GBuffer g, LBuffer l) { return g.color * l.light; }",
    )


@pytest.mark.parametrize("vendor", sorted(VENDORS))
def test_a_model_error_is_traced_to_model_stage_and_line_on_every_driver(vendor):
    model = _broken()
    line = first_line(model, "lighting") + 2  # the model's third line
    found = explain(_moderngl(VENDORS[vendor].format(line=line)), (model,), "point program")
    assert found is not None, f"{vendor}: the message was not understood"
    assert re.search(r"'broken', lighting stage, line 3: .*undefined_name", str(found)), str(found)
    assert "l.light += undefined_name;" in str(found)


def test_errors_outside_models_are_left_to_the_caller():
    model = _broken()
    assert explain(_moderngl(NVIDIA.format(line=12)), (model,), "point program") is None
    assert explain("error: out of memory", (model,), "point program") is None


def _nvidia_log(text: str) -> str:
    """Mesa's messages rewritten in NVIDIA's format (what the same error reads like on an NVIDIA driver)."""
    return re.sub(r"(?m)^(\d+):(\d+)\(\d+\): error: (.*)$", r"\1(\2) : error C1503: \3", text)


@pytest.mark.gl
def test_an_nvidia_driver_s_message_names_model_stage_and_line(monkeypatch):
    """The deferred pipeline compiled by a context that reports errors as NVIDIA's driver does."""
    from omnirender.gl import GLEngine

    engine = GLEngine(size=(32, 32), samples=0, pipeline="deferred")
    real = engine.ctx.program

    def program(**kwargs):
        try:
            return real(**kwargs)
        except Exception as exc:
            raise type(exc)(_nvidia_log(str(exc))) from None

    monkeypatch.setattr(engine.ctx, "program", program)
    try:
        with pytest.raises(om.gl.ShadingModelError, match=r"'broken', lighting stage, line 3: .*undefined_name"):
            engine.render(om.Node("s", [_broken()(), om.Sphere()]))
    finally:
        engine.release()
