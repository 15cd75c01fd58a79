"""Run the bad-input corpus: every case in its own process, with a timeout and a memory limit.

``python badinput_runner.py [--batch I/N] [--json OUT] [--only SUBSTRING]``

The runner imports omnirender and its Python dependencies once, then forks a
child per case (cheap: the imports are shared), so each case is isolated: a
crash kills only its child, a hang is killed at the case's timeout, and a
child that tries to take more than :data:`MEMORY_LIMIT` of address space gets a
MemoryError.  The child reports how the case ended through a pipe; the
runner classifies it:

* ``clear``: refused with an exception of a documented kind whose message
  names what is wrong (the case's key words) and is not a raw library message;
* ``handled``: tricky but valid input gave the right result (the case checks it);
* ``unclear``: refused, but with a raw exception type or message;
* ``silent``: bad input accepted (or a valid one gave a wrong result);
* ``crash``: the process died (a signal, a MemoryError, an exit without a report);
* ``hang``: the case ran past its timeout.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import re
import resource
import select
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

#: Address space a case may use (GL through llvmpipe needs about 0.8 GB of it).
MEMORY_LIMIT = 4 << 30
#: Exception types that may carry a clear refusal.
CLEAR_TYPES = ("ValueError", "TypeError", "OSError", "RuntimeError", "LookupError", "OmnirenderError")
#: Exception types that are never a clear refusal (Python or a library speaking, not omnirender).
RAW_TYPES = (
    "AttributeError",
    "IndexError",
    "OverflowError",
    "ZeroDivisionError",
    "RecursionError",
    "FloatingPointError",
    "NameError",
    "UnboundLocalError",
    "AssertionError",
    "NotImplementedError",
    "UnicodeError",
    "SystemError",
)
#: Messages written by Python, numpy or a renderer's library rather than by omnirender.
RAW_MESSAGES = re.compile(
    "|".join(
        [
            r"object has no attribute",
            r"unsupported operand",
            r"could not convert",
            r"invalid literal for",
            r"not subscriptable",
            r"object is not iterable",
            r"NoneType",
            r"cannot convert float NaN",
            r"int too large",
            r"drjit|nanobind|incompatible function arguments",
            r"Traceback",
            r"out of bounds for axis",
            r"setting an array element",
            r"could not be broadcast",
            r"index out of range",
            r"division by zero",
            r"maximum recursion depth",
            r"not JSON serializable",
            r"can't decode byte",
            r"ufunc",
            r"^\S+$",
        ]
    )
)


def preimport() -> None:
    """What every case may use, imported before forking (no threads, no GL context, no Mitsuba)."""
    import numpy  # noqa: F401
    import trimesh  # noqa: F401  (mesh files that are not plain OBJ)
    import yaml  # noqa: F401
    from PIL import Image  # noqa: F401

    import omnirender as om
    import omnirender.cli  # noqa: F401
    import omnirender.povray  # noqa: F401
    import omnirender.radiance  # noqa: F401
    import omnirender.scene.files  # noqa: F401
    import omnirender.scene.mesh_scene  # noqa: F401
    import omnirender.techniques  # noqa: F401

    om.gl._load()  # painters registered; no context yet


def classify(case: object, report: dict) -> str:
    """The class of one case's outcome (see the module docs)."""
    outcome = report.get("outcome")
    if outcome in ("hang", "crash"):
        return outcome
    if report.get("type") == "MemoryError":
        return "crash"
    kind = case.kind  # type: ignore[attr-defined]
    if outcome == "completed":
        return "handled" if kind in ("handle", "either") else "silent"
    if report.get("type") == "AssertionError" and report.get("in_case"):
        return "silent"  # the case's own check failed: the input was accepted and gave a wrong result
    if kind == "handle":
        return "unclear"  # valid input refused
    return "clear" if is_clear(case, report) else "unclear"


def is_clear(case: object, report: dict) -> bool:
    mro = report.get("mro", [])
    if report.get("type") in RAW_TYPES or not any(t in mro for t in CLEAR_TYPES):
        return False
    message = report.get("message", "")
    if len(message) < 20 or RAW_MESSAGES.search(message):
        return False
    lowered = message.lower()
    return all(word.lower() in lowered for word in case.words)  # type: ignore[attr-defined]


def run_case(case: object, root: Path) -> dict:
    """Fork a child for ``case``; returns its report (with ``outcome``)."""
    read_fd, write_fd = os.pipe()
    started = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(read_fd)
        code = 0
        try:
            _child(case, root, write_fd)
        except BaseException:  # noqa: BLE001 - reported below through the exit code
            code = 3
        finally:
            os._exit(code)
    os.close(write_fd)
    chunks: list[bytes] = []
    deadline = started + case.timeout  # type: ignore[attr-defined]
    status = None
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(read_fd)
            return {"outcome": "hang", "seconds": time.monotonic() - started}
        ready, _, _ = select.select([read_fd], [], [], min(left, 0.5))
        if ready:
            data = os.read(read_fd, 1 << 16)
            if data:
                chunks.append(data)
                continue
            break  # the child closed the pipe (finished or died)
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
    if status is None:
        # the pipe closed: wait for the child (bounded by the deadline)
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            if time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                os.close(read_fd)
                return {"outcome": "hang", "seconds": time.monotonic() - started}
            time.sleep(0.002)
    os.close(read_fd)
    seconds = time.monotonic() - started
    if os.WIFSIGNALED(status):
        return {"outcome": "crash", "signal": os.WTERMSIG(status), "seconds": seconds}
    try:
        report = json.loads(b"".join(chunks).decode("utf-8"))
    except ValueError:
        return {"outcome": "crash", "exit": os.WEXITSTATUS(status), "seconds": seconds}
    report["seconds"] = seconds
    return report


def _child(case: object, root: Path, fd: int) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    folder = Path(tempfile.mkdtemp(prefix="case-", dir=root))
    os.chdir(folder)
    report: dict
    try:
        case.run(folder)  # type: ignore[attr-defined]
        report = {"outcome": "completed"}
    except BaseException as exc:  # noqa: BLE001 - every way a case can end is reported
        tb = traceback.extract_tb(exc.__traceback__)
        in_case = bool(tb) and tb[-1].filename.endswith("badinput_cases.py")
        report = {
            "outcome": "raised",
            "type": type(exc).__name__,
            "mro": [c.__name__ for c in type(exc).__mro__],
            "message": " ".join(str(exc).split())[:2000],
            "in_case": in_case,
            "where": f"{tb[-1].filename}:{tb[-1].lineno}" if tb else "",
        }
    data = json.dumps(report).encode("utf-8")
    while data:
        written = os.write(fd, data)
        data = data[written:]
    os.close(fd)


def run(batch: tuple[int, int] = (0, 1), only: str | None = None) -> list[dict]:
    """Run the corpus (or one batch of it); returns one result dict per case."""
    sys.path.insert(0, str(Path(__file__).parent))
    from badinput_cases import CASES

    preimport()
    gc.collect()
    gc.freeze()  # children then never touch (and copy) the parent's objects to collect them
    index, count = batch
    selected = [c for i, c in enumerate(CASES) if i % count == index and (only is None or only in c.id)]
    results = []
    with tempfile.TemporaryDirectory(prefix="omnirender-badinput-") as tmp:
        for case in selected:
            report = run_case(case, Path(tmp))
            results.append(
                {
                    "id": case.id,
                    "category": case.category,
                    "class": classify(case, report),
                    "type": report.get("type", ""),
                    "message": report.get("message", "")[:300],
                    "where": report.get("where", ""),
                    "seconds": round(report.get("seconds", 0.0), 3),
                }
            )
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", default="0/1", help="I/N: run every N-th case starting at I")
    parser.add_argument("--json", help="write the results to this file")
    parser.add_argument("--only", help="run only the cases whose id contains this")
    parser.add_argument("-v", "--verbose", action="store_true", help="print every case")
    args = parser.parse_args()
    index, count = (int(v) for v in args.batch.split("/"))
    results = run((index, count), args.only)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    totals: dict[str, int] = {}
    for r in results:
        totals[r["class"]] = totals.get(r["class"], 0) + 1
        if args.verbose or r["class"] not in ("clear", "handled"):
            print(f"{r['class']:8s} {r['id']:50s} {r['type']}: {r['message'][:150]} {r['where']}")
    print(f"{len(results)} cases: " + ", ".join(f"{k} {v}" for k, v in sorted(totals.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
