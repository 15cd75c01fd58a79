"""GL state goes through the state applier: raw state writes and ``forget()`` calls are counted and may only go.

The GL engine sets state through :class:`~omnirender.gl.engine.state.RasterApplier` (it issues a call only for
what changed and knows what GL holds).  The modules that *are* the state layer may write GL state: the applier
and its kinds (``engine/state.py``, ``engine/attributes.py``), the context helpers the kinds call
(``engine/context.py``) and the state snapshots of the compositing rules (``engine/glstate.py``).  Everything
else in ``omnirender/gl`` and ``omnirender/compositing`` (which draws inside the engine's passes) writes none.

``forget()`` tells the applier that GL may hold anything; it is left only where code the engine does not know
ran, each listed in ``FORGETS`` with the reason.
"""

from __future__ import annotations

import ast
import pathlib
import re

import omnirender

PACKAGE = pathlib.Path(omnirender.__file__).parent
ROOTS = ("gl", "compositing")
#: the state layer: these modules set GL state by design
STATE_MODULES = {"gl/engine/state.py", "gl/engine/attributes.py", "gl/engine/context.py", "gl/engine/glstate.py"}
#: moderngl context attributes whose assignment sets GL state
STATE_ATTRIBUTES = {
    "blend_func", "blend_equation", "depth_func", "cull_face", "front_face", "wireframe", "polygon_offset",
    "point_size", "line_width", "scissor", "viewport", "color_mask", "depth_mask", "provoking_vertex",
}  # fmt: skip
#: moderngl context methods that set GL state
STATE_CALLS = {"enable", "disable", "enable_only", "enable_direct", "disable_direct"}
#: raw GL entry points that set state
RAW_STATE = re.compile(
    r"^gl(Enable|Disable|Stencil\w*|ColorMask\w*|DepthMask|SampleMask\w*|Scissor|Blend\w*|DepthFunc|CullFace"
    r"|FrontFace|Viewport|PolygonOffset|LineWidth|PointSize|PolygonMode)$"
)

#: raw state writes left outside the state layer: (module, function) -> why.  None are left.
RAW_WRITES: dict[tuple[str, str], str] = {}

#: applier.forget() calls left: (module, function) -> (how many, why)
FORGETS: dict[tuple[str, str], tuple[int, str]] = {
    ("gl/engine/frame.py", "forget_gl_state"): (
        1,
        "the public escape hatch engine.forget_gl_state(): a plug-in drawer made raw GL calls the engine cannot see",
    ),
    ("gl/engine/frame.py", "reset_gl_state"): (
        2,
        "the public escape hatch engine.reset_gl_state(): every kind issued at its default whatever GL holds "
        "(forget first), then nothing assumed because the caller goes on with raw calls (forget after)",
    ),
    ("gl/engine/frame.py", "_custom"): (
        1,
        "after a custom pass: the application's function may have changed any GL state and binding",
    ),
}


def _scan_source(module: str, text: str) -> tuple[list[tuple[str, str, str]], list[tuple[str, str]]]:
    """(raw state writes, applier forget() calls) of one module's source, each with the function it is in."""
    writes: list[tuple[str, str, str]] = []
    forgets: list[tuple[str, str]] = []

    def visit(node: ast.AST, function: str) -> None:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            function = node.name
        if isinstance(node, (ast.Assign, ast.AugAssign)):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                if isinstance(target, ast.Attribute) and target.attr in STATE_ATTRIBUTES:
                    writes.append((module, function, ast.unparse(target)))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            name, receiver = node.func.attr, ast.unparse(node.func.value)
            if name == "forget" and "applier" in receiver:
                forgets.append((module, function))
            elif (
                (name in STATE_CALLS and "ctx" in receiver)
                or RAW_STATE.match(name)
                or (name == "use" and not node.args and ("fbo" in receiver or "framebuffer" in receiver))
            ):
                writes.append((module, function, ast.unparse(node.func)))
        for child in ast.iter_child_nodes(node):
            visit(child, function)

    visit(ast.parse(text), "<module>")
    return writes, forgets


def _scan() -> tuple[list[tuple[str, str, str]], list[tuple[str, str]]]:
    """Every raw state write and applier forget() call of ``omnirender/gl`` and ``omnirender/compositing``."""
    writes: list[tuple[str, str, str]] = []
    forgets: list[tuple[str, str]] = []
    for root in ROOTS:
        for path in sorted((PACKAGE / root).rglob("*.py")):
            w, f = _scan_source(path.relative_to(PACKAGE).as_posix(), path.read_text())
            writes += w
            forgets += f
    return writes, forgets


def test_no_raw_gl_state_writes_outside_the_state_layer() -> None:
    writes, _ = _scan()
    outside = [w for w in writes if w[0] not in STATE_MODULES and (w[0], w[1]) not in RAW_WRITES]
    assert not outside, "set GL state through the applier (engine.apply_gl_state, between_frames...):\n" + "\n".join(
        f"{m}:{f}: {what}" for m, f, what in outside
    )
    left = {(m, f) for m, f, _ in writes if m not in STATE_MODULES}
    assert left == set(RAW_WRITES), f"RAW_WRITES lists writes that are gone: remove {set(RAW_WRITES) - left}"


def test_forget_calls_are_only_the_documented_ones() -> None:
    _, forgets = _scan()
    counts: dict[tuple[str, str], int] = {}
    for where in forgets:
        counts[where] = counts.get(where, 0) + 1
    assert counts == {where: n for where, (n, _) in FORGETS.items()}, counts
    assert sum(counts.values()) <= 4  # the number may only go down


def test_the_scan_finds_raw_state_writes_and_forgets() -> None:
    source = (
        "def f(ctx, fbo, raw, applier):\n    ctx.enable(ctx.BLEND)\n    ctx.depth_func = '<'\n    fbo.use()\n"
        "    raw.glStencilMaskSeparate(1, 2)\n    raw.glClear(0)\n    texture.use(0)\n    applier.forget()\n"
    )
    writes, forgets = _scan_source("m.py", source)
    assert [w[2] for w in writes] == ["ctx.enable", "ctx.depth_func", "fbo.use", "raw.glStencilMaskSeparate"]
    assert forgets == [("m.py", "f")]
