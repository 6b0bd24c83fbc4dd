"""The ``lmsbench`` command line. Each subcommand lives in its own module under
``experiments/commands/`` and exposes ``register(subparsers)``; this module finds them all.

Known errors (``lms200.LmsbenchError``, any ``OSError``: missing files, bad paths, unreachable
schedulers or devices) become one-line messages with exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from typing import Sequence

from lms200 import LmsbenchError

from . import commands


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="lmsbench",
        description="Fast feature extraction from 2-D laser rangefinders: a research testbed.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{commands.__name__}.{info.name}")
        if hasattr(module, "register"):
            module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    try:
        return int(args.func(args) or 0)
    except (LmsbenchError, OSError) as exc:  # OSError: missing files, bad paths, unreachable hosts, timeouts
        print(f"lmsbench {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"lmsbench {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
