"""The ``lmsbench`` command line. Each subcommand lives in its own module under
``experiments/commands/`` and exposes ``register(subparsers)``; this module finds them all.

Known errors (``lms200.LmsbenchError``, any ``OSError``: missing files, bad paths, unreachable
schedulers or devices) and bad options become one-line messages ``lmsbench CMD: error: ...`` with
exit status 2; Ctrl-C exits with 130 and one line. Anything else is a bug: one line saying so,
exit status 1 (``LMSBENCH_TRACEBACK=1`` shows the traceback).
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
from typing import Sequence

from lms200 import LmsbenchError

from . import commands
from .options import OneLineParser


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
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
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad option, already printed in one line (2)
        return int(exc.code or 0)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    name = " ".join(filter(None, (args.command, getattr(args, "lms200_command", None))))
    try:
        return int(args.func(args) or 0)
    except (LmsbenchError, OSError) as exc:  # OSError: missing files, bad paths, unreachable hosts, timeouts
        _end_progress_bars()
        print(f"lmsbench {name}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        _end_progress_bars()
        print(f"lmsbench {name}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug, not a user error: say so in one line
        if os.environ.get("LMSBENCH_TRACEBACK"):
            raise
        _end_progress_bars()
        print(f"lmsbench {name}: internal error: {type(exc).__name__}: {_one_line(exc)} "
              "(a bug in lmsbench; LMSBENCH_TRACEBACK=1 shows where)", file=sys.stderr)
        return 1


def _end_progress_bars() -> None:
    """Close the progress bars an error left open, so that the error starts a line of its own."""
    if "tqdm" not in sys.modules:
        return
    from tqdm import tqdm

    for bar in list(getattr(tqdm, "_instances", ())):
        bar.leave = False  # clear the bar's line: the error replaces it
        bar.close()


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 600 else text[:597] + "..."


if __name__ == "__main__":
    sys.exit(main())
