"""The ``omnirender`` command (see ``omnirender --help``).

Sub-commands: ``render`` a scene file with an engine, ``animate`` it (frames
on local processes or a Dask cluster, then a video), ``view`` it in an
interactive window, ``export`` it to another format, print ``info`` about it,
print the scene files' JSON ``schema``, list the ``engines`` available here,
and render the ``demo`` scene with every engine.  ``render``, ``view``,
``export`` and ``info`` also take a mesh file (OBJ, PLY, STL, OFF, glTF/GLB):
a scene is made around it with a fitted camera and default lights.

Exit codes (:data:`EXIT_CODES`): 0 success; 1 the work failed (the scene
file is malformed or refused, an engine is missing or fails, an output
cannot be written), reported in one line (``--debug`` shows the traceback);
2 the command line is wrong (unknown command or option, a bad value, a
scene file that does not exist or has an unknown extension, an output
extension nothing writes); 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import sys
import traceback
from pathlib import Path
from typing import Any

__all__ = ["main", "build_parser"]

_EXAMPLES = """\
examples:
  omnirender demo -o demo-output                 render the demo scene with every engine
  omnirender demo -e gl mitsuba                  ... with these engines only
  omnirender render scene.yaml -e gl -o out.png --size 800x600
  omnirender render scene.json -e mitsuba -o preview.png   a fast, denoised preview
  omnirender render scene.json -e mitsuba --quality final -o final.png
  omnirender render scene.yaml --mask '!debug'   skip nodes in the group 'debug'
  omnirender animate scene.yaml --frames 0-119 --fps 24 -e povray --workers 2 -o out.mp4
  omnirender animate scene.yaml --turntable 5 --scheduler tcp://host:8786 -o spin.mp4
  omnirender view scene.yaml                     interactive window (mouse: orbit/pan/zoom, h: help)
  omnirender export scene.yaml scene.glb         also .pov, .rib, .rad, .html and .obj, .ply, .stl (meshes)
  omnirender info scene.yaml                     tree, statistics, bounds, engines
  omnirender view bunny.obj                      a mesh file: fitted camera, default lights
  omnirender render bunny.obj -e povray          (render, animate, export and info take mesh files too)
  omnirender animate bunny.obj --turntable       a 5-second turntable video of a mesh file
  omnirender render scene.yaml --trusted         the file may use raw renderer text / files outside its folder

exit codes: 0 success, 1 the work failed (bad scene file, engine missing or failing), 2 bad command line,
  130 interrupted
"""


#: Extensions ``om.Image.save`` writes (checked before rendering).
IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
#: Scene-file extensions (mesh files are read too, see :func:`_load`).
SCENE_EXTENSIONS = (".json", ".yaml", ".yml")
USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")  # stages: loaded whole (cameras, lights), not as meshes
#: What the exit codes mean (also in ``omnirender --help``).
EXIT_CODES = {
    0: "success",
    1: "the work failed: a malformed or refused scene file, a missing or failing engine, an unwritable output",
    2: "the command line is wrong: a bad option or value, a missing scene file, an unknown file extension",
    130: "interrupted",
}


class UsageError(Exception):
    """A mistake in the command line (exit code 2)."""


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must be WIDTHxHEIGHT like 800x600, got {text!r}") from None
    if w <= 0 or h <= 0 or w > 16384 or h > 16384:
        raise argparse.ArgumentTypeError(f"size must be between 1x1 and 16384x16384, got {text!r}")
    return w, h


def _number(convert: type, minimum: float, strict: bool, what: str) -> Any:
    """An argparse type: ``convert(text)``, finite and > (``strict``) or >= ``minimum``."""

    def parse(text: str) -> Any:
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        above = value > minimum or (not strict and value == minimum)  # NaN is neither
        if not above or value == float("inf"):
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    return parse


_positive = _number(int, 0, True, "a positive integer")
_positive_float = _number(float, 0.0, True, "a positive number")
_count = _number(int, 0, False, "a whole number >= 0")


def _load(
    path: str,
    trusted: bool | argparse.Namespace = False,
    size: tuple[int, int] = (4, 3),
    animated: bool = False,
    engine: str = "gl",
) -> Any:
    """The scene of a scene file, or a scene made around a mesh file (for an image of ``size``, for ``engine``).

    ``trusted`` is a flag or the parsed arguments (``--trusted``,
    ``--allowed-root``, ``--strict``): the path policy of the file's references.
    ``animated``: a glTF file is read with its animations (``om.load_gltf``), staged with a fitted
    camera and the default lights when it has no camera of its own.
    """
    options = trusted if isinstance(trusted, argparse.Namespace) else None
    trusted = bool(getattr(options, "trusted", False)) if options is not None else bool(trusted)
    roots = list(getattr(options, "allowed_root", None) or [])
    strict = bool(getattr(options, "strict", False))
    from .scene.mesh_scene import mesh_suffixes

    mesh_exts = mesh_suffixes()
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in SCENE_EXTENSIONS + mesh_exts:
        raise UsageError(
            f"{path}: unknown extension {p.suffix!r}; give a scene file ({', '.join(SCENE_EXTENSIONS)}) "
            f"or a mesh file ({', '.join(mesh_exts)})"
        )
    if not p.exists():
        raise UsageError(f"scene file not found: {path}")
    if not p.is_file():
        raise UsageError(f"{path} is a folder, not a scene file")
    if suffix in USD_SUFFIXES:  # a whole stage: its cameras and lights, framed like a mesh when it has none
        from .formats.usd import load_usd
        from .scene.mesh_scene import framed

        return framed(load_usd(p, trusted=trusted), size[0] / size[1], engine not in SHADOWLESS_LIGHT_ENGINES)
    if animated and suffix in (".glb", ".gltf"):
        from .animation import load_gltf
        from .scene.mesh_scene import framed

        gltf = load_gltf(p, trusted=trusted, allowed_roots=roots, strict=strict)
        return framed(gltf, size[0] / size[1], engine not in SHADOWLESS_LIGHT_ENGINES)
    if suffix in mesh_exts:
        from .scene.mesh_scene import mesh_scene

        return mesh_scene(
            p,
            size[0] / size[1],
            fill_shadows=engine not in SHADOWLESS_LIGHT_ENGINES,
            trusted=trusted,
            allowed_roots=roots,
            strict=strict,
        )
    from .scene.files import load

    return load(p, trusted=trusted, allowed_roots=roots)


#: Engines that honour ``casts_shadows=False``.  For the others (path tracers) the fill and back lights
#: staged around a mesh file cast shadows, as those engines would make them anyway, without the warning
#: a scene asking for shadowless lights gets (the user asked for nothing).
SHADOWLESS_LIGHT_ENGINES = ("gl", "povray")


def _check_engine(name: str) -> None:
    from .options import did_you_mean
    from .render import _engines

    if name not in _engines:
        raise UsageError(f"unknown engine {name!r}; choose one of {', '.join(_engines)}{did_you_mean(name, _engines)}")


# -- sub-commands -----------------------------------------------------------
def _demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    for name in args.engine or ():
        _check_engine(name)
    written = run_demo(Path(args.output), size=args.size, engines=args.engine, quality=args.quality)
    return 0 if written else 1


def _engines(args: argparse.Namespace) -> int:
    from .render import engines, exporters

    for name, (ok, why) in engines().items():
        print(f"{name:10s} {'available' if ok else 'unavailable'}: {why}")
    for ext, desc in exporters().items():
        print(f"export {ext:5s} {desc}")
    return 0


def _render(args: argparse.Namespace) -> int:
    from .render import engine_status, render

    _check_engine(args.engine)
    options = _render_options(args)
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}-{args.engine}.png")
    if output.suffix.lower() not in IMAGE_EXTENSIONS:
        raise UsageError(f"cannot write an image to {str(output)!r}: use one of {', '.join(IMAGE_EXTENSIONS)}")
    ok, why = engine_status(args.engine, check=False)  # its packages; the engine itself says what else fails
    if not ok:
        raise RuntimeError(f"engine {args.engine!r} is not available here: {why}")
    scene = _load(args.scene, args, args.size, engine=args.engine)
    image = render(scene, engine=args.engine, size=args.size, **options)
    image.save(output)
    print(output)
    return 0


def _render_options(args: argparse.Namespace) -> dict[str, Any]:
    """Engine options from ``--spp`` and ``--mask`` (checked here, before anything is rendered)."""
    options: dict[str, Any] = {}
    if args.spp is not None:
        options.update(_spp_option(args.engine, args.spp))
    if args.quality is not None:
        if args.engine != "mitsuba":
            raise UsageError(f"--quality is an option of the mitsuba engine (for {args.engine}, use --spp)")
        options["quality"] = args.quality
    if args.mask is not None:
        from .core.mask import compile_mask

        try:
            compile_mask(args.mask)
        except Exception as exc:
            raise UsageError(f"bad --mask expression {args.mask!r}: {exc}") from None
        options["mask"] = args.mask
    return options


def _animate(args: argparse.Namespace) -> int:
    from .animation import animations, render_frames, turntable, video
    from .animation.frames import FRAME_EXTENSIONS
    from .animation.video import VIDEO_EXTENSIONS

    _check_engine(args.engine)
    if args.workers is not None and args.scheduler is not None:
        raise UsageError("give either --workers (local processes) or --scheduler (a Dask cluster), not both")
    options = _render_options(args)
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}-{args.engine}.mp4")
    ext = output.suffix.lower()
    if ext not in VIDEO_EXTENSIONS + FRAME_EXTENSIONS:
        raise UsageError(
            f"cannot write {str(output)!r}: use a video ({', '.join(VIDEO_EXTENSIONS)}) or a frame pattern "
            "such as frames/%05d.png"
        )
    if ext in FRAME_EXTENSIONS:
        pattern, make_video = str(output), False
    else:
        pattern, make_video = args.frames_dir or str(output.with_name(output.stem + "-frames") / "%05d.png"), True
    try:
        from .animation.animation import parse_frames

        frames = parse_frames(args.frames) if args.frames is not None else None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    scene = _load(args.scene, args, args.size, animated=True, engine=args.engine)
    if args.turntable is not None:
        turntable(scene, args.turntable, fps=args.fps or 24.0)
    elif not animations(scene):
        raise UsageError(f"{args.scene} holds no animation; add an om.Animation or use --turntable [SECONDS]")
    workers: Any = args.scheduler if args.scheduler is not None else args.workers
    report = render_frames(
        scene, frames, engine=args.engine, size=args.size, out=pattern, workers=workers, fps=args.fps,
        overwrite=args.overwrite, progress=False if args.quiet else None, **options,
    )  # fmt: skip
    print(f"frames: {report.summary()}", file=sys.stderr)
    if make_video:
        fps = args.fps or animations(scene)[0].fps
        video(report, output, fps=fps)
        print(output)
    else:
        print(Path(pattern).parent)
    return 0


def _spp_option(engine: str, spp: int) -> dict[str, Any]:
    """``--spp`` in each engine's terms: Mitsuba's samples per pixel, GL's MSAA samples, POV-Ray's antialiasing,
    Radiance's oversampling (``k x k`` rays per pixel with ``k * k`` nearest to ``spp``, at most 8 x 8)."""
    if engine == "povray":
        return {"antialias": spp > 1}
    if engine == "gl":
        return {"samples": _msaa_samples(spp)}
    if engine == "radiance":
        return {"oversample": max(1, min(8, round(spp**0.5)))}
    return {"spp": spp}


def _msaa_samples(spp: int) -> int:
    """The MSAA sample count GL can use for ``--spp``: the largest power of two <= spp (1: no multisampling).

    OpenGL multisampling takes powers of two; the GL engine further limits the
    count to the GPU's maximum.  A changed count is reported on stderr.
    """
    samples = 1 << (spp.bit_length() - 1)
    if samples != spp:
        print(f"omnirender render: note: --spp {spp} with gl uses {samples} MSAA samples (a power of two)",
              file=sys.stderr)  # fmt: skip
    return 0 if samples == 1 else samples


def _view(args: argparse.Namespace) -> int:
    scene = _load(args.scene, args, args.size)
    from .viewer import view

    view(scene, size=args.size, title=f"omnirender - {Path(args.scene).name}", duration=args.duration)
    return 0


def _export(args: argparse.Namespace) -> int:
    from .render import export, exporters

    ext = Path(args.output).suffix.lower()
    if ext not in exporters():
        raise UsageError(f"cannot export to {args.output!r}: use one of {', '.join(exporters())}")
    scene = _load(args.scene, args)
    export(scene, args.output)
    print(args.output)
    return 0


def _info(args: argparse.Namespace) -> int:
    scene = _load(args.scene, args)
    print(scene_report(scene, engines=not args.no_engines))
    return 0


def _schema(args: argparse.Namespace) -> int:
    import json

    from .scene.files import json_schema

    text = json.dumps(json_schema(), indent=2) + "\n"
    if args.output:
        from .fileio import atomic_write

        with atomic_write(args.output) as fh:
            fh.write(text)
        print(args.output)
    else:
        sys.stdout.write(text)
    return 0


def scene_report(scene: Any, engines: bool = True) -> str:
    """The text of ``omnirender info``: tree with paths, statistics, bounds, capable engines."""
    lines = ["tree:"]
    _tree(scene, lines, "  ", set(), "/" + scene.name)
    from .scene import statistics

    lines.append("statistics:")
    for key, value in dict(statistics(scene)).items():
        lines.append(f"  {key}: {value}")
    lines.append(f"bounds: {_bounds_text(scene)}")
    if engines:
        lines.append("engines:")
        for name, verdict in engine_support(scene).items():
            lines.append(f"  {name:10s} {verdict}")
    return "\n".join(lines)


#: Nesting shown by ``omnirender info`` before deeper nodes are summarised (a 100,000-level chain stays readable).
TREE_DEPTH = 40


def _tree(root: Any, lines: list[str], indent: str, seen: set[int], path: str) -> None:
    """List ``root`` at ``path`` (built on the way down: a shared node shows each of its paths); no recursion."""
    stack: list[tuple[Any, str, int]] = [(root, path, 0)]
    while stack:
        node, where, depth = stack.pop()
        pad = indent + "  " * depth
        if depth >= TREE_DEPTH:
            below = sum(1 for _ in node.walk())
            lines.append(f"{pad}{where}  ({below} node(s) from here down, not listed)")
            continue
        groups = f"  groups={sorted(node.groups)}" if node.groups else ""
        shared = "  (shared, listed above)" if id(node) in seen else ""
        lines.append(f"{pad}{where}{groups}{shared}")
        if shared:
            continue
        seen.add(id(node))
        children = []
        for item in node:
            if hasattr(item, "_compile_node"):
                children.append((item, f"{where}/{item.name}", depth + 1))
            else:
                text = repr(item)
                lines.append(f"{pad}  - {text if len(text) <= 100 else text[:97] + '...'}")
        stack.extend(reversed(children))


def _bounds_text(scene: Any) -> str:
    try:
        from .techniques import bounds

        box = bounds(scene)
    except Exception as exc:
        return f"unavailable ({type(exc).__name__}: {exc})"
    if box is None:
        return "empty"
    lo, hi = box
    return f"min {_vec(lo)}  max {_vec(hi)}"


def _vec(v: Any) -> str:
    return "(" + ", ".join(f"{float(x):.4g}" for x in v) + ")"


def engine_support(scene: Any) -> dict[str, str]:
    """Engine name -> whether it can render every shape class in ``scene`` (by handler look-up)."""
    import importlib

    from .core.handler import SIMPLIFY, registry
    from .render import _engines, engines

    shape_classes = {type(c) for n in scene.walk() for c in n.components if _is_shape(c)}
    out = {}
    for name, (ok, why) in engines().items():
        if not ok:
            out[name] = f"unavailable here: {why}"
            continue
        entry = _engines[name]
        module_name = entry.render.partition(":")[0] if isinstance(entry.render, str) else entry.render.__module__
        try:
            module = importlib.import_module(module_name)
        except Exception as exc:
            out[name] = f"cannot import {module_name}: {exc}"
            continue
        engine_cls = _engine_class(module)
        if engine_cls is None:
            out[name] = "available (no engine class to check handlers against)"
            continue
        missing = []
        for cls in sorted(shape_classes, key=lambda c: c.__name__):
            if not any(
                registry.lookup(engine_cls, engine_cls.service, k) or registry.lookup(engine_cls, SIMPLIFY, k)
                for k in cls.__mro__
            ):
                missing.append(cls.__name__)
        out[name] = "can render it" if not missing else f"cannot render: no handler for {', '.join(missing)}"
    return out


def _engine_class(module: Any) -> Any:
    """The engine class an adapter module exports (``GLEngine``, ``POVRayEngine``...), or None."""
    from .core.engine import Engine

    names = [n for n in getattr(module, "__all__", ()) if n.endswith("Engine")] + list(vars(module))
    for name in names:
        try:
            value = getattr(module, name)
        except AttributeError:
            continue
        if isinstance(value, type) and issubclass(value, Engine) and value.service != Engine.service:
            return value
    return None


def _is_shape(component: Any) -> bool:
    from .core.component import Shape

    return isinstance(component, Shape)


# -- parser -------------------------------------------------------------------
def _engine_names() -> str:
    """``gl (default), povray, mitsuba or radiance`` from the engine registry."""
    from .render import _engines

    names = [f"{n} (default)" if n == "gl" else n for n in _engines]
    return ", ".join(names[:-1]) + f" or {names[-1]}" if len(names) > 1 else "".join(names)


def _export_extensions() -> str:
    from .render import exporters

    return ", ".join(exporters())


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="omnirender",
        description="One scene graph, many engines: render, view, export and inspect scene files and mesh files.",
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    # --debug is also accepted after the command; SUPPRESS keeps a value given before it
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks on errors")
    reads = argparse.ArgumentParser(add_help=False)  # the commands that read a scene file
    reads.add_argument(
        "--trusted",
        action="store_true",
        help="trust the scene file: allow raw renderer text (povray.Raw, radiance.Raw) and files outside its folder",
    )
    reads.add_argument(
        "--allowed-root",
        action="append",
        metavar="DIR",
        help="a folder the file's references may lead into besides its own (repeatable)",
    )
    reads.add_argument(
        "--strict",
        action="store_true",
        help="fail instead of warning when a texture, material or extension of a mesh file cannot be used",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, help: str, scene: bool = True) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, parents=[common, reads] if scene else [common])

    scene_help = (
        "scene file (.json, .yaml), USD stage (.usd .usda .usdc .usdz) or mesh (.obj .ply .stl .off .glb .gltf)"
    )
    engine_help = f"{_engine_names()}; see 'omnirender engines'"
    quality_help = (
        "mitsuba only: preview (default: few samples, denoised when pyoidn is installed) or final (many samples)"
    )
    p = command("render", help="render a scene file or a mesh file to an image")
    p.add_argument("scene", help=scene_help)
    p.add_argument("-e", "--engine", default="gl", help=engine_help)
    p.add_argument("-o", "--output", help="image file (.png, .jpg...; default SCENE-ENGINE.png)")
    p.add_argument("--size", type=_size, default=(800, 600), help="image size WxH (default 800x600)")
    p.add_argument("--spp", type=_positive, help="samples per pixel (path tracers, antialiasing)")
    p.add_argument("--quality", choices=("preview", "final"), help=quality_help)
    p.add_argument("--mask", help="group mask expression, e.g. '!debug & (left|shared)'")
    p.set_defaults(func=_render)

    p = command("animate", help="render the frames of an animated scene (locally or on Dask) and make a video")
    p.add_argument(
        "scene",
        help=f"scene file with an om.Animation, an animated glTF or USD file; with --turntable any {scene_help}",
    )
    p.add_argument("-e", "--engine", default="gl", help=engine_help)
    p.add_argument("-o", "--output", help="video (.mp4, .gif...) or frame pattern (frames/%%05d.png)")
    p.add_argument("--frames", help="frame numbers: 0-119, 0-119:2 or 3,5,8 (default: the whole animation)")
    p.add_argument("--fps", type=_positive_float, help="frames per second (default: the animation's)")
    p.add_argument("--size", type=_size, default=(640, 480), help="image size WxH (default 640x480)")
    p.add_argument("--spp", type=_positive, help="samples per pixel (path tracers, antialiasing)")
    p.add_argument("--quality", choices=("preview", "final"), help=quality_help)
    p.add_argument("--mask", help="group mask expression, e.g. '!debug'")
    p.add_argument("--workers", type=_count, help="local worker processes (0: this process; default: one per core)")
    p.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786 (see 'dask scheduler')")
    p.add_argument(
        "--turntable",
        type=_positive_float,
        nargs="?",
        const=5.0,
        metavar="SECONDS",
        help="add a turntable of this length (default 5 s): the camera and lights orbit the scene",
    )
    p.add_argument("--frames-dir", help="frame pattern when writing a video (default OUTPUT-frames/%%05d.png)")
    p.add_argument("--overwrite", action="store_true", help="render frames again even if their files exist")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_animate)

    p = command("view", help="open a scene file or a mesh file in an interactive window")
    p.add_argument("scene", help=scene_help)
    p.add_argument("--size", type=_size, default=(960, 720), help="window size WxH (default 960x720)")
    p.add_argument("--duration", type=float, help="close the window after this many seconds (demos, tests)")
    p.set_defaults(func=_view)

    p = command("export", help=f"write a scene file or a mesh file in another format ({_export_extensions()})")
    p.add_argument("scene", help=scene_help)
    p.add_argument("output", help=f"output file; the extension chooses the format: {_export_extensions()}")
    p.set_defaults(func=_export)

    p = command("info", help="print the node tree with paths, statistics, bounds and capable engines")
    p.add_argument("scene", help=scene_help)
    p.add_argument("--no-engines", action="store_true", help="skip checking which engines can render it")
    p.set_defaults(func=_info)

    p = command("schema", help="print the JSON Schema of scene files (every registered type)", scene=False)
    p.add_argument("-o", "--output", help="write it to this file instead of printing it")
    p.set_defaults(func=_schema)

    p = command("engines", help="list engines and exporters and whether they work here", scene=False)
    p.set_defaults(func=_engines)

    p = command("demo", help="render the demo scene with every available engine (or those of -e)", scene=False)
    p.add_argument("-o", "--output", default="demo-output", help="folder for the images (default: demo-output)")
    p.add_argument("--size", type=_size, default=(640, 480), help="image size WxH (default 640x480)")
    p.add_argument(
        "-e", "--engine", nargs="+", metavar="ENGINE", help=f"render with these engines only ({_engine_names()})"
    )
    p.add_argument("--quality", choices=("preview", "final"), default="preview", help=quality_help)
    p.set_defaults(func=_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    from .progress import show_progress_lines

    show_progress_lines()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 0 for --help, 2 for usage errors
        return int(exc.code or 0)
    try:
        return int(args.func(args) or 0)
    except UsageError as exc:
        if args.debug:
            traceback.print_exc()
        parser.print_usage(sys.stderr)
        print(f"omnirender {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except Exception as exc:
        if args.debug:
            raise
        text = getattr(exc, "cli_message", None) or str(exc)  # e.g. "--trusted" rather than "trusted=True"
        message = " ".join(text.split()) or type(exc).__name__
        print(f"omnirender {args.command}: error: {message}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
