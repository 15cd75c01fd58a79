"""Soak benchmarks of issue 17: memory of long-running programs, large and deep scene files.

Each measurement runs in its own process (so peak memory is its own) and
prints its figures with a ratio against a baseline measured in the same run:

* ``oneshot``: process growth per ``om.render(engine="gl")`` call, against the
  old way of rendering once (a GL engine that creates and destroys its own
  context every call);
* ``persistent``: one GL engine drawing a new mesh and a new texture every
  frame (growth per frame, against the first frames);
* ``cloud``: loading a scene file of a large point cloud written as plain
  lists, base64 and a side-car ``.npz``, against ``numpy.load`` of the same
  array from a ``.npy`` file (disk speed), with each load's peak memory;
* ``deep``: save, load, build, bounds, pick, trace and a GL render of a chain
  of nested nodes at several depths; the ratio is the time per level at the
  deepest against the shallowest (1 = linear).  Operations that do not finish
  within ``--cap`` seconds are reported as such.
* ``hostile``: how long refusing a YAML "billion laughs" and a 100,000-level
  nesting takes.

Run: .venv/bin/python bench/soak.py [--quick] [--only NAME]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap
import time

PRELUDE = textwrap.dedent(
    """
    import json, os, resource, sys, tempfile, time
    import numpy as np
    import omnirender as om

    def rss_mb():
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6

    def peak_mb():
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3

    def scene():
        return om.Node("s", [om.Camera.look_at(eye=(0, 0, 5)), om.PointLight(position=(3, 3, 3)), om.Sphere()])
    """
)


def run(code: str, timeout: float) -> dict | None:
    """Run ``code`` (after the prelude) in a fresh process; its last output line is a JSON result."""
    try:
        proc = subprocess.run(
            [sys.executable, "-c", PRELUDE + textwrap.dedent(code)], capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:
        return None
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-2000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def oneshot(calls: int) -> None:
    code = """
    from omnirender.gl import GLEngine
    mode, calls = sys.argv_mode, sys.argv_calls
    def once():
        if mode == "shared":
            om.render(scene(), engine="gl", size=(64, 48))
        else:  # the old one-shot: a context created and destroyed per call
            engine = GLEngine(size=(64, 48))
            try:
                engine.render(scene())
            finally:
                engine.release()
    for _ in range(50):
        once()
    before, t = rss_mb(), time.perf_counter()
    for _ in range(calls):
        once()
    print(json.dumps({"kb_per_call": (rss_mb() - before) * 1000 / calls, "ms": (time.perf_counter() - t) * 1000 / calls,
                      "rss": rss_mb()}))
    """
    results = {}
    for mode in ("own-context", "shared"):
        src = code.replace("sys.argv_mode", repr(mode)).replace("sys.argv_calls", str(calls))
        results[mode] = run(src, 3600)
    old, new = results["own-context"], results["shared"]
    print(f"oneshot: {calls} calls of om.render(engine='gl') after 50 warm-up calls")
    print(f"  baseline (a context per call): {old['kb_per_call']:7.1f} KB/call  {old['ms']:6.1f} ms/call")
    print(f"  one hidden context per thread: {new['kb_per_call']:7.1f} KB/call  {new['ms']:6.1f} ms/call  "
          f"(RSS at the end {new['rss']:.0f} MB)")  # fmt: skip
    growth = max(new["kb_per_call"], 0.01)
    print(f"  ratio: {old['kb_per_call'] / growth:.0f}x less growth, {old['ms'] / new['ms']:.1f}x faster")


def persistent(frames: int) -> None:
    code = f"""
    from omnirender.gl import GLEngine
    engine = GLEngine(size=(64, 48))
    rng = np.random.default_rng(0)
    def frame():
        mesh = om.TriangleSet(rng.normal(size=(300, 3)).astype(np.float32))
        texture = om.Texture(rng.integers(0, 255, size=(32, 32, 4), dtype=np.uint8))
        lit = [om.Camera.look_at(eye=(0, 0, 8)), om.PointLight(position=(3, 3, 6)), texture, mesh]
        engine.render(om.Node("s", lit), read_depth=False)
    for _ in range(100):
        frame()
    first = rss_mb(); t = time.perf_counter()
    for _ in range({frames}):
        frame()
    print(json.dumps({{"kb_per_frame": (rss_mb() - first) * 1000 / {frames},
                      "ms": (time.perf_counter() - t) * 1000 / {frames}, "rss": rss_mb()}}))
    """
    r = run(code, 3600)
    print(f"persistent: one GL engine, {frames} frames each with a new mesh and texture")
    print(f"  growth {r['kb_per_frame']:.2f} KB/frame, {r['ms']:.1f} ms/frame, RSS at the end {r['rss']:.0f} MB")


def cloud(points: int) -> None:
    make = f"""
    folder = sys.argv_folder
    rng = np.random.default_rng(1)
    pts = rng.normal(size=({points}, 3)).astype(np.float32)
    s = om.Node("cloud", [om.PointSet(pts)])
    np.save(os.path.join(folder, "raw.npy"), pts)
    for arrays in ("lists", "auto", "npz"):
        om.save(s, os.path.join(folder, f"cloud-{{arrays}}.json"), arrays=arrays)
    print(json.dumps({{"ok": True}}))
    """
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        run(make.replace("sys.argv_folder", repr(folder)), 3600)
        load = """
        path = sys.argv_path
        warm = os.path.join(os.path.dirname(path), "warm.json")  # imports and type registry: not the load
        om.save(om.Node("warm", [om.PointSet([(0, 0, 0)])]), warm)
        om.load(warm)
        t = time.perf_counter()
        if path.endswith(".npy"):
            n = len(np.load(path))
        else:
            n = len(om.load(path).components[0].vertex_array())
        print(json.dumps({"s": time.perf_counter() - t, "peak": peak_mb(), "n": n}))
        """
        base = run(load.replace("sys.argv_path", repr(str(Path(folder) / "raw.npy"))), 3600)
        base_peak = run("print(json.dumps({'peak': peak_mb()}))", 600)["peak"]
        print(f"cloud: a scene file of {points:,} points ({points * 12 / 1e6:.0f} MB of float32)")
        print(f"  baseline numpy.load(.npy): {base['s']:.3f} s; a process that imports omnirender peaks at "
              f"{base_peak:.0f} MB")  # fmt: skip
        for arrays in ("lists", "auto", "npz"):
            scene_file = Path(folder) / f"cloud-{arrays}.json"
            size = scene_file.stat().st_size + sum(p.stat().st_size for p in Path(folder).glob("*.arrays.npz")
                                                   if arrays == "npz")  # fmt: skip
            r = run(load.replace("sys.argv_path", repr(str(scene_file))), 3600)
            label = {"lists": "plain lists", "auto": "base64 (default)", "npz": "side-car .npz"}[arrays]
            print(f"  {label:17s} {size / 1e6:7.1f} MB  load {r['s']:7.3f} s ({r['s'] / base['s']:5.1f}x numpy)  "
                  f"peak {r['peak']:6.0f} MB (+{r['peak'] - base_peak:.0f})")  # fmt: skip


DEEP = """
levels, op, folder = sys.argv_levels, sys.argv_op, sys.argv_folder
def chain(n):
    node = om.Node("n0", [om.Sphere(radius=0.5)])
    for i in range(1, n):
        node = om.Node(f"n{i}", [om.Translation(0.0001, 0, 0), node])
    return om.Node("root", [om.Camera.look_at(eye=(0, 0, 20)), node])
t = time.perf_counter()
root = chain(levels)
built = time.perf_counter() - t
path = os.path.join(folder, f"deep-{levels}.json")
if op == "load":
    om.save(root, path)
t = time.perf_counter()
if op == "build":
    pass
elif op == "build-top-down":
    top = om.Node("root"); node = top
    for i in range(levels):
        node = node.add(om.Node(f"n{i}", [om.Translation(0.0001, 0, 0)]))
elif op == "save":
    om.save(root, path)
elif op == "load":
    om.load(path)
elif op == "bounds":
    om.bounds(root)
elif op == "pick":
    om.pick(root, pixel=(32, 24), size=(64, 48))
elif op == "trace":
    om.trace(root)
elif op == "gl":
    om.render(root, engine="gl", size=(64, 48))
print(json.dumps({"s": built if op == "build" else time.perf_counter() - t}))
"""


def deep(levels: list[int], cap: float) -> None:
    import tempfile

    print(f"deep: a chain of nested nodes, each with a translation (cap {cap:.0f} s per run)")
    print("  " + "op".ljust(15) + "".join(f"{n:>12,}" for n in levels) + "   per-level ratio deepest/shallowest")
    with tempfile.TemporaryDirectory() as folder:
        for op in ("build", "build-top-down", "save", "load", "bounds", "pick", "trace", "gl"):
            times: list[float | None] = []
            for n in levels:
                if times and times[-1] is None:
                    times.append(None)
                    continue
                src = (DEEP.replace("sys.argv_levels", str(n)).replace("sys.argv_op", repr(op))
                       .replace("sys.argv_folder", repr(folder)))  # fmt: skip
                try:
                    r = run(src, cap + 30)
                except RuntimeError as exc:
                    last = str(exc).strip().splitlines()[-1]
                    times.append(None)
                    print(f"  {op}: {n} levels failed: {last[:100]}")
                    continue
                times.append(None if r is None or r["s"] > cap else r["s"])
            cells = "".join(f"{t:11.2f}s" if t is not None else f"{'> cap':>12}" for t in times)
            first, last = times[0], times[-1]
            ratio = (last / levels[-1]) / (first / levels[0]) if first and last else None
            print(f"  {op:15s}{cells}   {f'{ratio:.2f}' if ratio else 'n/a'}")


def hostile() -> None:
    code = """
    from omnirender.scene import files
    text = "format: omnirender-scene\\nversion: 1\\nroot: {node: x}\\nbomb:\\n  a: &a [x,x,x,x,x,x,x,x,x,x]\\n"
    for level, prev in zip("bcdefghi", "abcdefgh"):
        text += f"  {level}: &{level} [{','.join(['*' + prev] * 10)}]\\n"
    out = {}
    deep = "[" * 100000 + "]" * 100000
    for name, source, fmt in [("billion-laughs", text, "yaml"), ("json-100000-deep", deep, "json"),
                              ("yaml-100000-deep", "x: " + deep, "yaml")]:
        t = time.perf_counter()
        try:
            files.loads(source, fmt)
        except files.SceneFileError:
            pass
        out[name] = time.perf_counter() - t
    print(json.dumps(out))
    """
    r = run(code, 600)
    print("hostile: time to refuse")
    for name, seconds in r.items():
        print(f"  {name:20s} {seconds * 1000:8.1f} ms")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes (a few minutes)")
    parser.add_argument("--only", help="oneshot, persistent, cloud, deep or hostile")
    parser.add_argument("--cap", type=float, default=120.0, help="seconds before a deep-graph run counts as a hang")
    args = parser.parse_args()
    started = time.perf_counter()
    jobs = {
        "oneshot": lambda: oneshot(300 if args.quick else 2000),
        "persistent": lambda: persistent(500 if args.quick else 10000),
        "cloud": lambda: cloud(550_000 if args.quick else 5_500_000),
        "deep": lambda: deep([1000, 10000] if args.quick else [1000, 10000, 100000], args.cap),
        "hostile": hostile,
    }
    for name, job in jobs.items():
        if args.only in (None, name):
            job()
            print(flush=True)
    print(f"total {time.perf_counter() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
