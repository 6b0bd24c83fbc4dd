"""`lmsbench sweep SWEEP.yaml`: run a parameter sweep on Dask and write one tidy Parquet table.

Exit status: 0 when every cell succeeded, 1 when any failed (the table is written either way),
2 for a bad sweep file or setup error.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path

from experiments.options import SWEEP_OUTPUTS, SWEEP_OWNER, InputError, check_link, check_out, check_out_spares, check_yaml, count, path_arg, real_path, text, warnings_after_checks
from lms200.yamlio import SWEEP_SIZE_HINT


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep", help="run a parameter sweep (grid or random) on Dask; resumable")
    p.add_argument("sweep", type=path_arg, help="sweep file (YAML; see sweeps/*.yaml)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="tcp://HOST:PORT", type=text("a scheduler's address tcp://HOST:PORT"), help="use this running Dask scheduler")
    where.add_argument("--inprocess", "--local", dest="inprocess", action="store_true",
                       help="run in this process, without Dask (default: a local Dask cluster)")
    p.add_argument("--workers", type=count(1, 64), help="worker processes of the local cluster (default 2)")
    p.add_argument("--out", type=path_arg, help="sweep folder (default results/sweeps/NAME)")
    p.add_argument("--retry-failed", action="store_true", help="compute again the cells that failed before")
    p.add_argument("--no-progress", "--quiet", dest="no_progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from experiments.sweep import SweepSpecError, load_sweep, run_sweep
    from experiments.sweep.runner import spec_record

    executor = "inprocess" if args.inprocess else (args.scheduler if args.scheduler is not None else "local")
    if args.workers is not None and executor != "local":  # it was ignored
        instead = "--inprocess runs in this process" if args.inprocess else "--scheduler has workers of its own"
        raise InputError(f"--workers sets the processes of the local cluster; {instead}")
    args.workers = args.workers or 2
    from experiments.sweep.runner import check_executor, check_spec, plan_sweep, sweep_client

    check_executor(executor, args.workers)  # a --scheduler that is no address
    # the options first, then the sweep file, whose reading may warn (an old spelling): `--workers 3 --inprocess`
    # said that warning, then its error (a user error is one line)
    with contextlib.ExitStack() as stack:
        with warnings_after_checks():  # a refused run is its error alone, without a warning of what it read
            check_yaml(args.sweep, "a sweep file", size_hint=SWEEP_SIZE_HINT)
            spec = load_sweep(args.sweep)
            out = args.out = args.out or Path("results/sweeps") / spec.name  # named if a reader of stdout that goes away stops it
            check_link(out)  # a loop of links is said by name (real_path below leaves it as it is)
            # `sweep DIR/sweep.yaml --out DIR` lost a user's comments; the sweep.yaml a run wrote, as it wrote it, may
            # be run again (it is rewritten the same)
            own = real_path(args.sweep) == real_path(out / "sweep.yaml") and Path(args.sweep).read_text() == spec_record(spec)
            check_out_spares(out, SWEEP_OUTPUTS.files, [] if own else [args.sweep])
            check_out(out, writes=SWEEP_OUTPUTS, owner=SWEEP_OWNER)
            _check_same_sweep(out, spec.name)
            try:
                fn = check_spec(spec)
            except SweepSpecError as exc:  # an unknown kind or parameter name
                raise SweepSpecError(f"{args.sweep}: {exc}") from exc
            # `--out .` (or `sub/..`) names the current folder as text ("" is refused by path_arg); the library takes
            # it only as an absolute path (Path("") is Path("."), so run_sweep refuses both)
            folder = Path.cwd() if os.path.abspath(out) == os.getcwd() else out
            plan = plan_sweep(spec, folder, fn, args.retry_failed)  # the cells left, from the folder's cell files
            if plan.todo and executor not in ("local", "inprocess"):
                # reached within the checks, before their warnings are said: an unreachable --scheduler said the
                # repeated-draws warning, then 'Timed out trying to connect' (a user error is one line); only where
                # cells remain: a finished sweep ('0 computed, 2 already done') needs no scheduler
                executor = stack.enter_context(sweep_client(executor, args.workers))  # a Client, used as is
        if spec.kind in ("extract", "slam") and executor in ("local", "inprocess") and plan.todo:
            # compile once here (the workers then load the cache), not in every worker at the same time; a slam
            # sweep's SLAM kernels too (slam_vs_noise's first cell spent 36 s compiling them in the workers, unsaid)
            from experiments.progress import warm_up_kernels

            warm_up_kernels(slam=spec.kind == "slam")
        try:
            result = run_sweep(spec, folder, executor, workers=args.workers, retry_failed=args.retry_failed,
                               progress=not args.no_progress, checked=True, plan=plan)  # checked above: its warnings were said once
        except SweepSpecError as exc:  # an unknown kind or parameter name, found before any cell ran
            raise SweepSpecError(f"{args.sweep}: {exc}") from exc
    if result.failed:  # said first on stderr: a stdout whose reader went away stops at the summary below
        print(f"lmsbench sweep: {result.failed} of {result.total} cells failed (their `error` column says why; "
              f"--retry-failed computes them again)", file=sys.stderr)
    print(f"{spec.name}: {result.total} cells, {result.computed} computed, {result.skipped} already done, "
          f"{result.failed} failed")
    print(f"wrote {out / 'results.parquet'}, {out / 'results.csv'}")  # both tables, as others name every file
    if result.failed:
        errors = result.table.loc[result.table["status"] != "ok", "error"].value_counts()
        for text, n in errors.head(5).items():
            print(f"  {n} x {text}")
        return 1
    return 0


def _check_same_sweep(out: Path, name: str) -> None:
    """A sweep folder that holds another sweep (its sweep.yaml names another) is not written over:
    `sweep B.yaml --out A_folder` replaced A's sweep.yaml, results.parquet and results.csv with B's,
    exit 0 (A's cells stayed, but its table and record were gone). The same sweep, edited (a value
    added to its grid), still resumes there."""
    import yaml

    from lms200.yamlio import load as load_yaml

    record = out / "sweep.yaml"
    if not record.is_file():
        return
    try:
        held = load_yaml(record.read_text(encoding="utf-8"), words=True)  # an earlier version's record too
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return  # not a record of a sweep: check_out's business
    other = held.get("name") if isinstance(held, dict) else None
    if isinstance(other, str) and other != name:
        raise InputError(f"--out {out}: holds the sweep {other!r} (its sweep.yaml), not {name!r}: its results would be "
                         "replaced; give another folder (a sweep resumes in a folder of its own name)")
