"""The bad-input corpus (issue 17): every case refused clearly or handled; no hang, crash or silent garbage.

``badinput_cases.py`` holds the cases, ``badinput_runner.py`` runs each in its
own process with a timeout and a memory limit and classifies the outcome
(``python tests/badinput/badinput_runner.py -v`` prints every case).  The
corpus runs in two batches, one per xdist worker.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
RUNNER = HERE / "badinput_runner.py"
BATCHES = 2

sys.path.insert(0, str(HERE))
import badinput_runner  # noqa: E402
from badinput_cases import CASES, Case  # noqa: E402


def test_the_corpus_is_large_and_covers_every_category():
    assert len(CASES) >= 300
    assert len({c.id for c in CASES}) == len(CASES)
    categories = Counter(c.category for c in CASES)
    for category in ("scene files", "components", "arrays", "transforms and camera", "nodes",
                     "render options and sizes", "command line", "engine content", "deep graphs"):  # fmt: skip
        assert categories[category] >= 4, category
    assert {c.kind for c in CASES} <= {"refuse", "handle", "either"}


def _case(kind: str = "refuse", words: tuple[str, ...] = ()) -> Case:
    return Case("x", "test", lambda _t: None, kind, words)


@pytest.mark.parametrize(
    "report, kind, words, expected",
    [
        ({"outcome": "hang"}, "refuse", (), "hang"),
        ({"outcome": "crash"}, "refuse", (), "crash"),
        ({"outcome": "raised", "type": "MemoryError", "mro": ["MemoryError"]}, "refuse", (), "crash"),
        ({"outcome": "completed"}, "refuse", (), "silent"),
        ({"outcome": "completed"}, "handle", (), "handled"),
        ({"outcome": "raised", "type": "AssertionError", "in_case": True, "mro": []}, "handle", (), "silent"),
        ({"outcome": "raised", "type": "ValueError", "mro": ["ValueError"], "message": "x"}, "handle", (), "unclear"),
        (
            {
                "outcome": "raised",
                "type": "ValueError",
                "mro": ["ValueError"],
                "message": "Sphere: radius must be > 0, got -1.0",
            },
            "refuse",
            ("radius",),
            "clear",
        ),  # fmt: skip
        (
            {
                "outcome": "raised",
                "type": "ValueError",
                "mro": ["ValueError"],
                "message": "Sphere: radius must be > 0, got -1.0",
            },
            "refuse",
            ("center",),
            "unclear",
        ),  # fmt: skip
        (
            {
                "outcome": "raised",
                "type": "OverflowError",
                "mro": ["OverflowError", "ArithmeticError"],
                "message": "int too large to convert to float",
            },
            "refuse",
            (),
            "unclear",
        ),  # fmt: skip
        (
            {
                "outcome": "raised",
                "type": "ValueError",
                "mro": ["ValueError"],
                "message": "could not convert string to float: 'a'",
            },
            "refuse",
            (),
            "unclear",
        ),  # fmt: skip
        (
            {
                "outcome": "raised",
                "type": "AttributeError",
                "mro": ["AttributeError"],
                "message": "'str' object has no attribute 'category'",
            },
            "refuse",
            (),
            "unclear",
        ),  # fmt: skip
    ],
)
def test_outcomes_are_classified(report, kind, words, expected):
    assert badinput_runner.classify(_case(kind, words), report) == expected


def test_the_runner_sees_hangs_crashes_and_runaway_memory(tmp_path):
    """The runner itself: each way a process can go wrong is caught and named (a case of each, forked here)."""
    script = f"""
import os, signal, sys, time
sys.path.insert(0, {str(HERE)!r})
import badinput_runner as r
from badinput_cases import Case
from pathlib import Path
cases = [
    Case("hang", "t", lambda t: time.sleep(60), timeout=1.0),
    Case("segv", "t", lambda t: os.kill(os.getpid(), signal.SIGSEGV)),
    Case("memory", "t", lambda t: bytearray(8 << 30)),
    Case("exit", "t", lambda t: os._exit(7)),
    Case("silent", "t", lambda t: None),
    Case("clear", "t", lambda t: (_ for _ in ()).throw(ValueError("Sphere: radius must be > 0, got -1")),
         words=("radius",)),
]
print([r.classify(c, r.run_case(c, Path({str(tmp_path)!r}))) for c in cases])
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "['hang', 'crash', 'crash', 'crash', 'silent', 'clear']"


@pytest.mark.slow
@pytest.mark.parametrize("batch", range(BATCHES))
def test_every_bad_input_is_refused_clearly_or_handled(batch, tmp_path):
    out = tmp_path / "results.json"
    proc = subprocess.run(
        [sys.executable, str(RUNNER), "--batch", f"{batch}/{BATCHES}", "--json", str(out)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = json.loads(out.read_text())
    assert len(results) == len(CASES[batch::BATCHES])
    totals = Counter(r["class"] for r in results)
    bad = [f"{r['class']} {r['id']}: {r['type']}: {r['message']} ({r['where']})" for r in results
           if r["class"] not in ("clear", "handled")]  # fmt: skip
    assert not bad, f"{dict(totals)}\n" + "\n".join(bad)
