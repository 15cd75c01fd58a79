"""Generate the malicious asset files of tests/security (run: python tests/data_files/malicious/make_malicious.py).

Files in ``files/`` attack the loaders: path traversal, absolute paths, URIs,
symbolic links out of the folder, decompression bombs, counts that lie,
cycles, runaway nesting.  ``outside/`` holds the files they try to reach (no
loader may open them).  ``manifest.json`` says, per file, how it is loaded
and what must happen: ``"error"`` (an exception whose message matches
``match``) or ``"warning"`` (a DroppedContentWarning matching ``match``, and
the same load with ``strict=True`` raises).  Not the project's own assets:
every file here was written to break something.
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import struct
import zlib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
FILES = HERE / "files"
OUTSIDE = HERE / "outside"

TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
UVS = np.array([[0, 0], [1, 0], [0, 1]], np.float32)


def png(width: int, height: int, color: tuple[int, int, int] = (200, 40, 40)) -> bytes:
    """A small RGB PNG written by hand (no Pillow needed to regenerate the files)."""
    row = b"\x00" + bytes(color) * width
    return _png(width, height, 2, 8, zlib.compress(row * height))


def bomb_png(side: int = 30000) -> bytes:
    """A 1-bit grey PNG of side x side zero pixels: about 0.1 MB on disk, 900 million pixels decoded."""
    row = b"\x00" * (1 + (side + 7) // 8)
    comp = zlib.compressobj(9)
    chunks = [comp.compress(row) for _ in range(side)]
    chunks.append(comp.flush())
    return _png(side, side, 0, 1, b"".join(chunks))


def _png(width: int, height: int, color_type: int, depth: int, idat: bytes) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, depth, color_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def data_uri(data: bytes) -> str:
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode()


def gltf(buffer_uri: str | None = None, image: dict | None = None, **changes) -> dict:
    """A valid one-triangle glTF (positions and UVs in a data URI), changed by the arguments."""
    data = TRIANGLE.tobytes() + UVS.tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": buffer_uri or data_uri(data), "byteLength": len(data)}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    if image is not None:
        doc["images"] = [image]
        doc["textures"] = [{"source": 0}]
        doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        doc["meshes"][0]["primitives"][0]["material"] = 0
    doc.update(changes)
    return doc


def glb(doc: dict, binary: bytes = b"", json_length: int | None = None) -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\x00" * (-len(binary) % 4)
    body = struct.pack("<II", json_length if json_length is not None else len(text), 0x4E4F534A) + text
    if binary:
        body += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


OBJ_BODY = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"


def main() -> None:
    for folder in (FILES, OUTSIDE):
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
    (OUTSIDE / "secret.bin").write_bytes(TRIANGLE.tobytes() + UVS.tobytes())
    (OUTSIDE / "secret.mtl").write_text("newmtl m\nKd 1 0 0\n")
    (OUTSIDE / "secret.png").write_bytes(png(4, 4))
    (FILES / "ok.png").write_bytes(png(4, 4))
    (FILES / "bomb.png").write_bytes(bomb_png())
    (FILES / "garbage.png").write_bytes(b"\x89PNG\r\n\x1a\n" + os.urandom(64))
    (FILES / "triangle.obj").write_text(OBJ_BODY)
    os.symlink("../outside/secret.bin", FILES / "link.bin")
    os.symlink("../outside/secret.mtl", FILES / "link.mtl")
    os.symlink("../outside", FILES / "linkdir")
    secret_abs = str(OUTSIDE / "secret.bin")
    cases: dict[str, dict] = {}

    def add(name: str, content: str | bytes | dict, loader: str, expect: str, match: str) -> None:
        path = FILES / name
        if isinstance(content, dict):
            content = json.dumps(content)
        path.write_bytes(content.encode() if isinstance(content, str) else content)
        cases[name] = {"loader": loader, "expect": expect, "match": match}

    refused = "leads outside|absolute path|symbolic link|file: URI|trusted=True"
    # -- glTF: references --------------------------------------------------------------------------
    add("gltf-buffer-traversal.gltf", gltf("../outside/secret.bin"), "gltf", "error", "leads outside")
    add("gltf-buffer-deep-traversal.gltf", gltf("../../../../../../../../etc/passwd"), "gltf", "error", "leads outside")
    add("gltf-buffer-etc-passwd.gltf", gltf("/etc/passwd"), "gltf", "error", "absolute path")
    add("gltf-buffer-absolute-secret.gltf", gltf(secret_abs), "gltf", "error", "absolute path")
    add("gltf-buffer-file-uri.gltf", gltf("file:///etc/passwd"), "gltf", "error", "absolute path")
    add("gltf-buffer-file-uri-host.gltf", gltf("file://evil.example/etc/passwd"), "gltf", "error", "another host")
    add("gltf-buffer-percent-traversal.gltf", gltf("%2e%2e/outside/secret.bin"), "gltf", "error", "leads outside")
    add("gltf-buffer-backslash-traversal.gltf", gltf("..\\outside\\secret.bin"), "gltf", "error", "leads outside")
    add("gltf-buffer-windows-absolute.gltf", gltf("C:\\Windows\\win.ini"), "gltf", "error", "absolute path")
    add("gltf-buffer-unc.gltf", gltf("\\\\server\\share\\x.bin"), "gltf", "error", "absolute path")
    add("gltf-buffer-symlink-out.gltf", gltf("link.bin"), "gltf", "error", "symbolic link")
    add("gltf-buffer-symlink-dir.gltf", gltf("linkdir/secret.bin"), "gltf", "error", "symbolic link")
    add("gltf-buffer-http.gltf", gltf("http://evil.example/x.bin"), "gltf", "error", "never downloads")
    add("gltf-buffer-https.gltf", gltf("https://evil.example/x.bin"), "gltf", "error", "never downloads")
    add("gltf-buffer-nul.gltf", gltf("ok.png\u0000../x"), "gltf", "error", "NUL")
    add("gltf-buffer-missing.gltf", gltf("missing.bin"), "gltf", "error", "does not exist")
    add("gltf-image-traversal.gltf", gltf(image={"uri": "../outside/secret.png"}), "gltf", "error", "leads outside")
    add("gltf-image-absolute.gltf", gltf(image={"uri": str(OUTSIDE / "secret.png")}), "gltf", "error", "absolute")
    add("gltf-image-http.gltf", gltf(image={"uri": "http://evil.example/x.png"}), "gltf", "warning", "images\\[0\\]")
    add("gltf-image-missing.gltf", gltf(image={"uri": "missing.png"}), "gltf", "warning", "does not exist")
    add("gltf-image-bomb.gltf", gltf(image={"uri": "bomb.png"}), "gltf", "warning", "MAX_IMAGE_PIXELS")
    add("gltf-image-garbage.gltf", gltf(image={"uri": "garbage.png"}), "gltf", "warning", "not a readable image")
    add("gltf-image-javascript.gltf", gltf(image={"uri": "javascript:alert(1)"}), "gltf", "warning", "never downloads")
    bomb = bomb_png()
    embedded = TRIANGLE.tobytes() + UVS.tobytes() + bomb
    doc = gltf(image={"bufferView": 2, "mimeType": "image/png"})
    doc["buffers"] = [{"byteLength": len(embedded)}]
    doc["bufferViews"].append({"buffer": 0, "byteOffset": 60, "byteLength": len(bomb)})
    add("glb-embedded-bomb.glb", glb(doc, embedded), "gltf", "warning", "MAX_IMAGE_PIXELS")
    # -- glTF: counts, cycles, nesting --------------------------------------------------------------
    lie = gltf()
    lie["accessors"][0]["count"] = 100_000
    add("gltf-count-lie.gltf", lie, "gltf", "error", "do not fit")
    lie = gltf()
    lie["accessors"][0]["count"] = 1_000_000_000
    add("gltf-count-beyond-limit.gltf", lie, "gltf", "error", "MAX_DECODED_BYTES")
    lie = gltf()
    del lie["accessors"][0]["bufferView"]
    lie["accessors"][0]["count"] = 2**40
    add("gltf-count-without-buffer.gltf", lie, "gltf", "error", "MAX_DECODED_BYTES|MAX_INDICES")
    lie = gltf()
    lie["bufferViews"][0]["byteOffset"] = 2**62
    add("gltf-view-offset-lie.gltf", lie, "gltf", "error", "outside its buffer")
    lie = gltf()
    lie["bufferViews"][0]["byteStride"] = 2**31
    add("gltf-stride-lie.gltf", lie, "gltf", "error", "do not fit")
    lie = gltf()
    lie["buffers"][0]["byteLength"] = 2**40
    add("gltf-buffer-length-lie.gltf", lie, "gltf", "error", "fewer than its byteLength")
    lie = gltf(indices=None)
    lie["meshes"][0]["primitives"][0]["indices"] = 0
    lie["accessors"][0] = {"bufferView": 0, "componentType": 5125, "count": 9, "type": "SCALAR"}
    lie["accessors"].append({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"})
    lie["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 2
    lie.pop("indices")
    add("gltf-index-out-of-range.gltf", lie, "gltf", "error", "out of range|index")
    cycle = gltf()
    cycle["nodes"] = [{"children": [1]}, {"children": [0], "mesh": 0}]
    add("gltf-node-cycle.gltf", cycle, "gltf", "error", "its own ancestor")
    deep = gltf()
    deep["nodes"] = [{"children": [i + 1]} for i in range(2000)] + [{"mesh": 0}]
    add("gltf-node-nesting.gltf", deep, "gltf", "error", "MAX_NESTING")
    add("gltf-json-nesting.gltf", '{"asset": ' + "[" * 5000 + "]" * 5000 + "}", "gltf", "error", "nested")
    add("glb-json-length-lie.glb", glb(gltf(), json_length=2**31), "gltf", "error", "truncated")
    add("glb-truncated.glb", glb(gltf())[:30], "gltf", "error", "truncated|JSON")
    add("gltf-required-extension.gltf", gltf(extensionsRequired=["EVIL_ext"]), "gltf", "error", "EVIL_ext")
    add("gltf-optional-extension.gltf", gltf(extensionsUsed=["EVIL_ext"]), "gltf", "warning", "EVIL_ext")
    # -- OBJ / MTL -----------------------------------------------------------------------------------
    add("obj-mtllib-traversal.obj", "mtllib ../outside/secret.mtl\n" + OBJ_BODY, "mesh", "error", "leads outside")
    add("obj-mtllib-absolute.obj", "mtllib /etc/passwd\n" + OBJ_BODY, "mesh", "error", "absolute path")
    add("obj-mtllib-symlink.obj", "mtllib link.mtl\n" + OBJ_BODY, "mesh", "error", "symbolic link")
    add("obj-mtllib-missing.obj", "mtllib missing.mtl\n" + OBJ_BODY, "mesh", "warning", "material library")
    add("obj-mtllib-http.obj", "mtllib http://evil.example/x.mtl\n" + OBJ_BODY, "mesh", "warning", "never downloads")
    for name, line, expect, match in [
        ("traversal", "map_Kd ../outside/secret.png", "error", "leads outside"),
        ("absolute", f"map_Kd {OUTSIDE / 'secret.png'}", "error", "absolute path"),
        ("missing", "map_Kd missing.png", "warning", "texture 'missing.png' dropped"),
        ("bomb", "map_Kd bomb.png", "warning", "MAX_IMAGE_PIXELS"),
        ("garbage", "map_Kd garbage.png", "warning", "not a readable image"),
        ("http", "map_Kd http://evil.example/x.png", "warning", "never downloads"),
        ("bump", "map_Kd ok.png\nmap_Bump ../outside/secret.png", "warning", "map_Bump"),
    ]:
        (FILES / f"mtl-{name}.mtl").write_text(f"newmtl m\nKd 1 1 1\n{line}\n")
        add(f"obj-map-{name}.obj", f"mtllib mtl-{name}.mtl\nusemtl m\n" + OBJ_BODY, "mesh", expect, match)
    add("obj-index-out-of-range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 99\n", "mesh", "error", "index|range|invalid")
    add("obj-huge-index.obj", "v 0 0 0\nf 1 2 99999999999999999999\n", "mesh", "error", "index|range|invalid")
    # -- PLY / OFF / STL -----------------------------------------------------------------------------
    ply = "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
    ply += "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    add("ply-count-lie.ply", ply, "mesh", "error", "MAX_VERTICES|announces")
    ply = "ply\nformat binary_little_endian 1.0\nelement vertex 50000000\nproperty float x\nproperty float y\n"
    ply += "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    add("ply-binary-count-lie.ply", ply.encode() + TRIANGLE.tobytes(), "mesh", "error", "announces|cannot load")
    ply = "ply\nformat ascii 1.0\ncomment TextureFile ../outside/secret.png\nelement vertex 3\nproperty float x\n"
    ply += "property float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\n"
    ply += "property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"
    add("ply-texture-traversal.ply", ply, "mesh", "error", "leads outside")
    add("off-count-lie.off", "OFF\n3000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "mesh", "error", "MAX_VERTICES")
    add("off-face-lie.off", "OFF\n3 90000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "mesh", "error", "announces")
    stl = b"\x00" * 80 + struct.pack("<I", 1_000_000_000) + b"\x00" * 50
    add("stl-count-lie.stl", stl, "mesh", "error", "cannot load|no triangles|invalid")

    # -- scene files -----------------------------------------------------------------------------------
    def scene(*contents: dict) -> dict:
        return {"format": "omnirender-scene", "version": 1, "root": {"node": "s", "contents": list(contents)}}

    add("scene-mesh-traversal.json", scene({"type": "MeshFile", "path": "../outside/x.obj"}), "scene", "error", refused)
    add("scene-mesh-absolute.json", scene({"type": "MeshFile", "path": "/etc/passwd"}), "scene", "error", "absolute")
    add("scene-texture-absolute.json", scene({"type": "Texture", "image": "/etc/passwd"}), "scene", "error", "absolute")
    add(
        "scene-texture-traversal.json",
        scene({"type": "Texture", "image": "../outside/secret.png"}),
        "scene",
        "error",
        "leads outside",
    )
    add(
        "scene-texture-http.json",
        scene({"type": "Texture", "image": "http://evil.example/x.png"}),
        "scene",
        "error",
        "never downloads",
    )
    add(
        "scene-texture-bomb.json", scene({"type": "Texture", "image": "bomb.png"}), "scene", "error", "MAX_IMAGE_PIXELS"
    )
    add(
        "scene-sidecar-traversal.json",
        scene({"type": "TriangleSet", "vertices": {"$file": "../outside/x.npy"}}),
        "scene",
        "error",
        "leads outside",
    )
    add(
        "scene-mesh-with-escaping-mtl.json",
        scene({"type": "MeshFile", "path": "obj-mtllib-traversal.obj"}),
        "scene",
        "error",
        "leads outside",
    )
    add(
        "scene-mesh-claims-trust.json",
        scene({"type": "MeshFile", "path": "obj-mtllib-traversal.obj", "trusted": True}),
        "scene",
        "error",
        "unknown parameter|not a parameter|trusted",
    )
    add(
        "scene-raw.json",
        scene({"type": "povray.Raw", "text": '#include "/etc/passwd"'}),
        "scene",
        "error",
        "trusted-only",
    )
    laughs = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
        f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
        for i in range(9)
    )
    add("scene-billion-laughs.yaml", laughs, "scene", "error", "alias|expan")
    add(
        "scene-nesting.json",
        '{"format": "omnirender-scene", "version": 1, "root": ' + "[" * 5000 + "]" * 5000 + "}",
        "scene",
        "error",
        "nested",
    )
    cycle_scene = {
        "format": "omnirender-scene",
        "version": 1,
        "root": {"node": "s", "$id": "a", "contents": [{"$ref": "a"}]},
    }
    add("scene-cycle.json", cycle_scene, "scene", "error", "ref|defined|cycle|itself")
    (HERE / "manifest.json").write_text(json.dumps(cases, indent=1, sort_keys=True) + "\n")
    print(f"{len(cases)} malicious files in {FILES}")


if __name__ == "__main__":
    main()
