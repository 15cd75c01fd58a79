"""Worker processes import the main script again: a clear error when its rendering call is not guarded.

Local worker processes are started with ``spawn`` (a fresh interpreter per
worker: forking a process that holds GL contexts or threads is unsafe).  Each
worker imports the main script, so a script that calls ``om.render_frames(...,
workers=2)`` at its top level, outside ``if __name__ == "__main__":``, would
start workers from every worker; multiprocessing stops that with a long
bootstrapping traceback in each worker and the frames fail as "the worker
process died".  :func:`check_main_guard` finds the line of the main script that
led to the call and, when it is not under the guard, says so before any process
starts.  Interactive sessions, notebooks and ``python -c`` have no script to
import and pass.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

__all__ = ["check_main_guard", "MainGuardError"]


class MainGuardError(RuntimeError):
    """The main script starts worker processes outside ``if __name__ == "__main__":``."""


def check_main_guard(what: str) -> None:
    """Raise :class:`MainGuardError` when the main script runs ``what`` at import, outside the guard."""
    main = sys.modules.get("__main__")
    filename = getattr(main, "__file__", None)
    if main is None or not filename or not str(filename).endswith(".py"):
        return
    line = _main_line(vars(main))
    if line is None:
        return
    try:
        tree = ast.parse(Path(filename).read_text(encoding="utf-8"), filename)
    except (OSError, SyntaxError, ValueError, UnicodeDecodeError):
        return
    if any(_is_guard(node) and node.lineno <= line <= (node.end_lineno or line) for node in ast.walk(tree)):
        return
    raise MainGuardError(
        f"{what} starts worker processes, and each imports your script {filename} again, which would run "
        f'line {line} again in every worker: put the code that renders under `if __name__ == "__main__":` '
        "(as for any process pool), or pass workers=0 to render in this process"
    )


def _main_line(main_globals: dict) -> int | None:
    """The line of the main script's top-level code that is running now (None: not called from it)."""
    frame = sys._getframe(1)
    line = None
    while frame is not None:
        if frame.f_globals is main_globals and frame.f_code.co_name == "<module>":
            line = frame.f_lineno
        frame = frame.f_back
    return line


def _is_guard(node: ast.AST) -> bool:
    """``if __name__ == "__main__":`` (either side of ``==``)."""
    if not isinstance(node, ast.If) or not isinstance(node.test, ast.Compare):
        return False
    test = node.test
    if len(test.ops) != 1 or not isinstance(test.ops[0], ast.Eq):
        return False
    sides = [test.left, test.comparators[0]]
    names = [s for s in sides if isinstance(s, ast.Name) and s.id == "__name__"]
    strings = [s for s in sides if isinstance(s, ast.Constant) and s.value == "__main__"]
    return len(names) == 1 and len(strings) == 1
