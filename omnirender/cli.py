"""The ``omnirender`` command (see ``omnirender --help``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["main"]


def _demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    run_demo(Path(args.output), size=tuple(int(v) for v in args.size.lower().split("x")))
    return 0


def _engines(args: argparse.Namespace) -> int:
    from .render import engines

    for name, (ok, why) in engines().items():
        print(f"{name:10s} {'available' if ok else 'unavailable'}: {why}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="omnirender", description="One scene graph, many engines.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="render the demo scene with every available engine")
    p.add_argument("-o", "--output", default="demo-output", help="folder for the images (default: demo-output)")
    p.add_argument("--size", default="640x480", help="image size WxH (default 640x480)")
    p.set_defaults(func=_demo)
    p = sub.add_parser("engines", help="list engines and whether they work here")
    p.set_defaults(func=_engines)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except Exception as exc:
        if args.debug:
            raise
        print(f"omnirender: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
