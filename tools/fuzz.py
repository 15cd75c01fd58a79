"""Fuzzing the loaders: mutated glTF/GLB, OBJ (+MTL), PLY, STL, OFF and scene files.

Every mutated file must give a *clear error* (a ValueError or OSError, which
omnirender's own errors are) or load into a graph whose bounds are finite;
never another exception (TypeError, KeyError, IndexError, RecursionError,
MemoryError... a crash), never a hang (more than ``--hang`` seconds, default
10) and never memory beyond a bound (the process runs under an address-space
limit, ``--memory``, default 4 GiB).

The CI runs a bounded number of examples through hypothesis
(tests/security/test_fuzz.py); the long campaign is this command::

    nice -n 19 python -m tools.fuzz --examples 100000 [--loaders gltf,glb,obj,ply,stl,off,scene] [--seed 1]

It runs the loaders in child processes (a crash of the interpreter is a
finding too, with the input kept), prints what it tried and found, and writes
every finding to ``--out`` (default ``fuzz-findings/``).  The mutations
(truncation, random bytes, interesting integers at aligned offsets, numbers
in text formats replaced by huge, negative or non-finite ones, JSON values
replaced, keys deleted, nesting added, counts, indices, strides, offsets and
URIs changed) are in :func:`mutate`, shared with the CI tests.
"""

from __future__ import annotations

import argparse
import base64
import copy
import json
import os
import random
import re
import resource
import signal
import struct
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
import zlib
from pathlib import Path
from typing import Any

LOADERS = ("gltf", "glb", "obj", "ply", "stl", "off", "scene")
#: Exceptions that are clear refusals; anything else is a finding.
CLEAR = (ValueError, OSError)
INTERESTING_INTS = [
    0,
    1,
    -1,
    2,
    3,
    4,
    7,
    255,
    256,
    65535,
    65536,
    2**31 - 1,
    2**31,
    2**32 - 1,
    2**32,
    2**53,
    2**63,
    -(2**31),
]
INTERESTING_TEXT = ["0", "-1", "1e309", "-1e309", "nan", "inf", "4294967295", "99999999999999999999", "-2147483648",
                    "3.4e38", "1e-320", "", "x", "1/2/3", "0/0"]  # fmt: skip
INTERESTING_STRINGS = ["../secret.bin", "/etc/passwd", "http://x/y", "file:///etc/passwd", "", "a\x00b",
                       "data:application/octet-stream;base64,AAAA", "%2e%2e/x", "\\\\h\\s", "C:\\x"]  # fmt: skip
TRIANGLES = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0, 0.5)]


class Hang(Exception):
    """A loader ran past the hang threshold."""


# -- seeds: small valid files of every format -------------------------------------------------------------
def _png(width: int = 4, height: int = 4) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    raw = (b"\x00" + b"\xc8\x28\x28" * width) * height
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def gltf_doc(binary: bool = False) -> tuple[dict[str, Any], bytes]:
    """A two-triangle indexed, textured glTF: (document, binary chunk); data URIs when not ``binary``."""
    pos = struct.pack("<12f", *[c for v in TRIANGLES for c in v])
    uv = struct.pack("<8f", 0, 0, 1, 0, 0, 1, 1, 1)
    idx = struct.pack("<6H", 0, 1, 2, 1, 3, 2)
    png = _png()
    blob = pos + uv + idx + b"\x00" * 4 + png  # the image starts at byte 96
    doc: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [0, 0, 0]}, {"mesh": 0, "scale": [1, 1, 1]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": [1, 1, 1, 1]}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "buffers": [{"byteLength": len(blob)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": 96, "byteLength": len(png)},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0.5]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    if not binary:
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    return doc, blob


def glb_bytes(doc: dict[str, Any], blob: bytes) -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\x00" * (-len(blob) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


OBJ = """mtllib m.mtl
o quad
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0.5
vt 0 0
vt 1 0
vt 0 1
vt 1 1
vn 0 0 1
usemtl skin
f 1/1/1 2/2/1 3/3/1
f 2/2/1 4/4/1 3/3/1
"""
MTL = "newmtl skin\nKa 0.2 0.2 0.2\nKd 0.8 0.5 0.3\nKs 0.5 0.5 0.5\nNs 20\nd 1\nmap_Kd tex.png\n"
PLY_ASCII = """ply
format ascii 1.0
element vertex 4
property float x
property float y
property float z
property uchar red
property uchar green
property uchar blue
element face 2
property list uchar int vertex_indices
end_header
0 0 0 255 0 0
1 0 0 0 255 0
0 1 0 0 0 255
1 1 0.5 255 255 0
3 0 1 2
3 1 3 2
"""
OFF = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0.5\n3 0 1 2\n3 1 3 2\n"


def ply_binary() -> bytes:
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")  # fmt: skip
    body = b"".join(struct.pack("<3f", *v) for v in TRIANGLES)
    body += struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B3i", 3, 1, 3, 2)
    return header.encode() + body


def stl_binary() -> bytes:
    tris = [(TRIANGLES[0], TRIANGLES[1], TRIANGLES[2]), (TRIANGLES[1], TRIANGLES[3], TRIANGLES[2])]
    body = b"".join(struct.pack("<12fH", 0, 0, 1, *a, *b, *c, 0) for a, b, c in tris)
    return b"\x00" * 80 + struct.pack("<I", len(tris)) + body


def stl_ascii() -> bytes:
    lines = ["solid t"]
    for a, b, c in [(TRIANGLES[0], TRIANGLES[1], TRIANGLES[2]), (TRIANGLES[1], TRIANGLES[3], TRIANGLES[2])]:
        lines += ["facet normal 0 0 1", " outer loop"] + [f"  vertex {x} {y} {z}" for x, y, z in (a, b, c)]
        lines += [" endloop", "endfacet"]
    return ("\n".join(lines) + "\nendsolid t\n").encode()


def scene_doc() -> dict[str, Any]:
    return {
        "format": "omnirender-scene",
        "version": 1,
        "definitions": [{"$id": "mat", "type": "Material", "diffuse": [1, 0.4, 0.6]}],
        "root": {"node": "scene", "groups": ["a"], "contents": [
            {"type": "Camera", "eye": [4, 3, 6], "center": [0, 0, 0], "up": [0, 1, 0], "fov": 35},
            {"type": "PointLight", "position": [5, 5, 5]},
            {"node": "body", "$id": "body", "contents": [
                {"type": "Translation", "offset": [0, 1, 0]},
                {"$ref": "mat"},
                {"type": "Texture", "image": "tex.png"},
                {"type": "Torus", "major_radius": 1, "minor_radius": 0.3},
                {"type": "TriangleSet", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "indices": [[0, 1, 2]]},
                {"type": "MeshFile", "path": "m.obj"}]},
            {"$ref": "body"}]},
    }  # fmt: skip


# -- mutations ---------------------------------------------------------------------------------------------
def mutate_bytes(data: bytes, rnd: random.Random) -> bytes:
    """One to four byte-level changes: truncation, random bytes, interesting integers at aligned offsets."""
    out = bytearray(data)
    for _ in range(rnd.randint(1, 4)):
        op = rnd.randrange(7)
        n = len(out)
        if op == 0 and n:
            del out[rnd.randrange(n) :]
        elif op == 1 and n:
            out[rnd.randrange(n)] = rnd.randrange(256)
        elif op == 2:
            at = rnd.randrange(n + 1)
            out[at:at] = bytes(rnd.randrange(256) for _ in range(rnd.randint(1, 16)))
        elif op == 3 and n > 4:
            at = rnd.randrange(0, n - 4) // 4 * 4
            value = rnd.choice(INTERESTING_INTS) & 0xFFFFFFFF
            out[at : at + 4] = struct.pack("<I", value)
        elif op == 4 and n:
            a = rnd.randrange(n)
            del out[a : a + rnd.randint(1, 64)]
        elif op == 5 and n:
            a = rnd.randrange(n)
            piece = out[a : a + rnd.randint(1, 64)]
            out[a:a] = piece * rnd.randint(1, 8)
        elif op == 6 and n > 8:
            at = rnd.randrange(n - 8)
            out[at : at + 8] = struct.pack("<d", rnd.choice([float("nan"), float("inf"), 1e308, -1e308, 1e-310]))
    return bytes(out)


_NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:e-?\d+)?")


def mutate_text(data: bytes, rnd: random.Random) -> bytes:
    """Numbers replaced by interesting ones, lines deleted, duplicated or swapped, truncation."""
    text = data
    for _ in range(rnd.randint(1, 4)):
        op = rnd.randrange(5)
        numbers = list(_NUMBER.finditer(text))
        lines = text.split(b"\n")
        if op <= 1 and numbers:
            m = rnd.choice(numbers)
            text = text[: m.start()] + rnd.choice(INTERESTING_TEXT).encode() + text[m.end() :]
        elif op == 2 and lines:
            del lines[rnd.randrange(len(lines))]
            text = b"\n".join(lines)
        elif op == 3 and lines:
            i = rnd.randrange(len(lines))
            lines[i:i] = [lines[i]] * rnd.randint(1, 50)
            text = b"\n".join(lines)
        else:
            text = mutate_bytes(text, rnd)
    return text


def _paths(value: Any) -> list[tuple]:
    """Paths to every value of a JSON document, at most 40 levels down (iteratively: documents may be deep)."""
    out: list[tuple] = []
    stack: list[tuple[tuple, Any]] = [((), value)]
    while stack:
        prefix, current = stack.pop()
        out.append(prefix)
        if len(prefix) >= 40:
            continue
        if isinstance(current, dict):
            stack.extend(((*prefix, k), v) for k, v in current.items())
        elif isinstance(current, list):
            stack.extend(((*prefix, i), v) for i, v in enumerate(current))
    return out


def _copy(value: Any) -> Any:
    try:
        return copy.deepcopy(value)
    except RecursionError:  # a deep nesting: share it (the document is only written out)
        return value


def _random_value(rnd: random.Random, depth: int = 0) -> Any:
    kind = rnd.randrange(8)
    if kind == 0:
        return rnd.choice(INTERESTING_INTS)
    if kind == 1:
        return rnd.choice([float("nan"), float("inf"), -1.5, 1e300, 0.5])
    if kind == 2:
        return rnd.choice(INTERESTING_STRINGS)
    if kind == 3:
        return None
    if kind == 4:
        return rnd.choice([True, False])
    if kind == 5 and depth < 3:
        return [_random_value(rnd, depth + 1) for _ in range(rnd.randint(0, 4))]
    if kind == 6 and depth < 3:
        return {rnd.choice(["uri", "count", "type", "node", "children", "$ref"]): _random_value(rnd, depth + 1)}
    nested: Any = 0
    for _ in range(rnd.choice([10, 300, 900])):
        nested = [nested]
    return nested


def mutate_json(doc: Any, rnd: random.Random) -> Any:
    """JSON values replaced (counts, offsets, strides, indices, URIs...), keys deleted, lists grown, nesting."""
    doc = _copy(doc)
    for _ in range(rnd.randint(1, 3)):
        paths = [p for p in _paths(doc) if p]
        if not paths:
            return _random_value(rnd)
        path = rnd.choice(paths)
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        key = path[-1]
        op = rnd.randrange(5)
        if op <= 1:
            parent[key] = _random_value(rnd)
        elif op == 2 and isinstance(parent, dict):
            del parent[key]
        elif op == 3 and isinstance(parent, list):
            parent.append(_copy(parent[key]) if rnd.random() < 0.7 else _random_value(rnd))
        elif isinstance(parent[key], int) and not isinstance(parent[key], bool):
            parent[key] = parent[key] + rnd.choice([-1, 1, 4, -4, 2**16, 2**31, -(2**31)])
        else:
            parent[key] = _random_value(rnd)
    return doc


def _dumps(doc: Any) -> bytes:
    try:
        return json.dumps(doc).encode()
    except RecursionError:  # nesting deeper than the encoder goes: write it by hand
        return b'{"asset": ' + b"[" * 5000 + b"]" * 5000 + b"}"


def mutate(loader: str, rnd: random.Random, mutations: bool = True) -> dict[str, bytes]:
    """A mutated input for ``loader``: ``{file name: bytes}`` (the first name is the file to load).

    ``mutations=False`` gives the valid seed files themselves.
    """
    tex = _png()

    def maybe(p: float) -> bool:
        return mutations and rnd.random() < p

    if loader in ("gltf", "glb"):
        doc, blob = gltf_doc(binary=loader == "glb")
        if maybe(0.6):
            doc = mutate_json(doc, rnd)
        if loader == "glb":
            try:
                data = glb_bytes(doc, blob) if isinstance(doc, dict) else _dumps(doc)
            except (TypeError, ValueError, RecursionError):
                data = b"glTF"
        else:
            data = _dumps(doc)
        if maybe(0.5):
            data = mutate_bytes(data, rnd) if loader == "glb" or rnd.random() < 0.5 else mutate_text(data, rnd)
        return {f"model.{loader}": data, "tex.png": tex, "buf.bin": blob}
    if loader == "obj":
        obj, mtl = OBJ.encode(), MTL.encode()
        if maybe(0.8):
            obj = mutate_text(obj, rnd)
        if maybe(0.4):
            mtl = mutate_text(mtl, rnd)
        return {"model.obj": obj, "m.mtl": mtl, "tex.png": mutate_bytes(tex, rnd) if maybe(0.2) else tex}
    if loader == "ply":
        data = PLY_ASCII.encode() if not mutations or rnd.random() < 0.5 else ply_binary()
        if mutations:
            data = mutate_text(data, rnd) if rnd.random() < 0.5 else mutate_bytes(data, rnd)
        return {"model.ply": data}
    if loader == "stl":
        data = stl_binary() if not mutations or rnd.random() < 0.6 else stl_ascii()
        if mutations:
            data = mutate_bytes(data, rnd) if rnd.random() < 0.6 else mutate_text(data, rnd)
        return {"model.stl": data}
    if loader == "off":
        return {"model.off": mutate_text(OFF.encode(), rnd) if mutations else OFF.encode()}
    if loader == "scene":
        doc = mutate_json(scene_doc(), rnd) if maybe(0.8) else scene_doc()
        data = _dumps(doc)
        if maybe(0.3):
            data = mutate_text(data, rnd)
        return {"scene.json": data, "tex.png": tex, "m.obj": OBJ.encode(), "m.mtl": MTL.encode()}
    raise ValueError(f"unknown loader {loader!r} (known: {', '.join(LOADERS)})")


# -- running one input ---------------------------------------------------------------------------------------
def load(folder: Path, name: str) -> Any:
    """Load ``folder/name`` the way an application would; returns the graph (or shape)."""
    import omnirender as om

    path = folder / name
    if name.endswith((".gltf", ".glb")):
        return om.load_gltf(path)
    if name.endswith(".json"):
        root = om.load(path)
        stack, seen = [root], set()
        while stack:
            node = stack.pop()
            if id(node) in seen:
                continue
            seen.add(id(node))
            for item in node.items:
                if isinstance(item, om.Node):
                    stack.append(item)
                elif isinstance(item, om.MeshFile):
                    item.load()
                elif isinstance(item, om.Texture):
                    item.image_array()
        return root
    mesh = om.MeshFile(path)
    mesh.load()
    return om.Node("mesh", [mesh])


def check(files: dict[str, bytes], folder: Path) -> str:
    """Write ``files`` into ``folder``, load the first; "clear" (a clear error), "loaded" or raise the finding."""
    import numpy as np

    import omnirender as om

    for old in folder.iterdir():
        old.unlink()
    for name, data in files.items():
        (folder / name).write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            graph = load(folder, next(iter(files)))
        except CLEAR:
            return "clear"
        box = om.bounds(graph)
    if box is not None and not np.all(np.isfinite(np.asarray(box, dtype=np.float64))):
        raise AssertionError(f"loaded with non-finite bounds {box}")
    return "loaded"


def _alarm(signum: int, frame: Any) -> None:
    raise Hang("the loader ran past the hang threshold")


def child(loader: str, start: int, count: int, seed: int, hang: float, memory: int, out: Path) -> None:
    """Run inputs ``start .. start + count`` of ``loader``; prints one JSON line of counts and findings."""
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    signal.signal(signal.SIGALRM, _alarm)
    folder = Path(tempfile.mkdtemp(prefix=f"fuzz-{loader}-"))
    current = out / f"current-{loader}-{os.getpid()}"
    counts = {"clear": 0, "loaded": 0, "findings": 0}
    slowest = 0.0
    check(mutate(loader, random.Random(0), mutations=False), folder)  # imports and caches: not an input's time
    for i in range(start, start + count):
        rnd = random.Random(f"{seed}-{loader}-{i}")
        files = mutate(loader, rnd)
        current.write_text(
            json.dumps({"index": i, "files": {k: base64.b64encode(v).decode() for k, v in files.items()}})
        )
        t = time.perf_counter()
        signal.setitimer(signal.ITIMER_REAL, hang)
        try:
            counts[check(files, folder)] += 1
        except BaseException as exc:  # noqa: BLE001 - every other outcome is a finding
            signal.setitimer(signal.ITIMER_REAL, 0)
            counts["findings"] += 1
            finding = out / f"{loader}-{i}.json"
            finding.write_text(json.dumps({
                "loader": loader, "index": i, "seed": seed, "error": f"{type(exc).__name__}: {exc}"[:2000],
                "traceback": traceback.format_exc()[-4000:],
                "files": {k: base64.b64encode(v).decode() for k, v in files.items()},
            }))  # fmt: skip
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        slowest = max(slowest, time.perf_counter() - t)
    current.unlink(missing_ok=True)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({**counts, "slowest": slowest, "peak": peak}))


def campaign(args: argparse.Namespace) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    loaders = args.loaders.split(",")
    per = args.examples // len(loaders)
    totals = {"clear": 0, "loaded": 0, "findings": 0, "crashes": 0}
    slowest, peak = 0.0, 0
    started = time.time()
    for loader in loaders:
        done = 0
        while done < per:
            count = min(args.batch, per - done)
            cmd = [sys.executable, "-m", "tools.fuzz", "--child", loader, str(done), str(count), str(args.seed),
                   str(args.hang), str(args.memory), str(out)]  # fmt: skip
            proc = subprocess.run(cmd, capture_output=True, text=True)
            lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
            if proc.returncode == 0 and lines:
                result = json.loads(lines[-1])
                for key in ("clear", "loaded", "findings"):
                    totals[key] += result[key]
                slowest = max(slowest, result["slowest"])
                peak = max(peak, result["peak"])
                done += count
            else:  # the interpreter died: keep the input it was on, go on after it
                totals["crashes"] += 1
                current = sorted(out.glob(f"current-{loader}-*"))
                index = done
                if current:
                    index = json.loads(current[-1].read_text())["index"]
                    current[-1].rename(out / f"{loader}-{index}-crash.json")
                (out / f"{loader}-{index}-crash.log").write_text(proc.stderr[-8000:])
                totals["findings"] += 1
                done = index + 1
            print(f"  {loader}: {done}/{per} ({time.time() - started:.0f} s) {totals}", flush=True)
    tried = totals["clear"] + totals["loaded"] + totals["findings"]
    print(f"fuzz campaign: {tried} inputs ({', '.join(loaders)}), seed {args.seed}, {time.time() - started:.0f} s")
    print(f"  clear errors {totals['clear']}, loaded {totals['loaded']}, findings {totals['findings']} "
          f"(interpreter crashes {totals['crashes']})")  # fmt: skip
    print(f"  slowest input {slowest:.2f} s (hang threshold {args.hang} s); peak RSS of a worker "
          f"{peak / (1 << 20):.0f} MiB (address-space limit {args.memory / (1 << 30):.1f} GiB)")  # fmt: skip
    print(f"  findings are in {out}/")
    return 1 if totals["findings"] else 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "--child":
        loader, start, count, seed, hang, memory, out = argv[1:8]
        child(loader, int(start), int(count), int(seed), float(hang), int(memory), Path(out))
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=10000, help="inputs in all, split over the loaders")
    parser.add_argument("--loaders", default=",".join(LOADERS))
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--hang", type=float, default=10.0, help="seconds after which an input counts as a hang")
    parser.add_argument("--memory", type=int, default=4 << 30, help="address-space limit of a worker, bytes")
    parser.add_argument("--batch", type=int, default=2000, help="inputs per worker process")
    parser.add_argument("--out", default="fuzz-findings")
    return campaign(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
