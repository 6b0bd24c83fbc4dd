"""`lmsbench slam INPUT --out DIR`: odometry-free EKF-SLAM over a simulator run, a CARMEN log or a bag."""

from __future__ import annotations

from lms200.finite import fixed
from lms200.yamlio import load as load_yaml

import argparse
import bisect
import math
import sys
import time
from typing import TYPE_CHECKING, Any
from pathlib import Path

import numpy as np

if TYPE_CHECKING:
    from slam import SlamConfig

from experiments.logargs import add_log_options, read_log_options
from experiments.overrides import check_set_once, extractor_overrides, set_option
from experiments.options import (said_after_checks, SLAM_OUTPUTS, SLAM_OWNER, SLAM_RECORD_KEYS, InputError, check_file, check_log, check_methods, check_out, check_out_spares, check_simulate_finished, check_yaml,
                                 count, missing_message, path_arg, positive, text)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("slam", help="odometry-free SLAM (scan matching + pose graph, or the paper's EKF) over a simulator folder, CARMEN log or bag "
                                    "(trajectory.tum, keyframes.tum, map.json, metrics.json, config.yaml, slam.png)")
    p.add_argument("input", type=path_arg, help="simulator output folder (scans.clf, groundtruth.tum, world.json), CARMEN log or bag")
    p.add_argument("--out", type=path_arg, required=True, help="output folder")
    p.add_argument("--config", type=path_arg, help="a SLAM config.yaml (its 'slam' section or a flat mapping)")
    p.add_argument("--preset", choices=("default", "paper"),
                   help="default: scan matching + pose graph with loop closures; paper: the paper's EKF "
                        "(constant velocity, line landmarks). Default: the config's, 'default'")
    p.add_argument("--no-paper-baseline", action="store_true",
                   help="with the default preset, do not also run the paper preset for the comparison table")
    p.add_argument("--extractor", type=text("an extraction method's name"), help="feature extraction method (default: the config's, 'sensor')")
    p.add_argument("--set", dest="params", action="append", type=set_option, default=[], metavar="extractor.[METHOD.]FIELD=VALUE",
                   help="override a field of the SLAM's extractor, as compare --set and sweeps spell it (repeatable; "
                        "it joins the config's extractor_params)")
    p.add_argument("--association", choices=("nn", "jcbb"), help="paper preset: data association (default: the config's)")
    p.add_argument("--corners", action="store_true", help="paper preset: add corner landmarks")
    p.add_argument("--odometry", action="store_true",
                   help="use the input's odometry as the motion input (default pipeline: the prediction the scan "
                        "matcher starts from and the turns it may look for; paper preset: the filter's motion)")
    p.add_argument("--no-odometry-baseline", action="store_true",
                   help="do not also run the filter with odometry for the comparison table")
    p.add_argument("--relations", type=path_arg, help="relations file (default: NAME.relations beside a log)")
    p.add_argument("--every", "--stride", dest="every", type=count(1), default=1,
                   help="keep every N-th scan (decimation; default 1, every scan; --stride as in compare)")
    # a log may last longer than the simulated runs' hour: > 0, no floor (one that keeps a single scan is refused
    # after the read); one at or above the log's own rate keeps every scan
    p.add_argument("--rate-hz", type=positive("scans/s"), help="decimate to about this many scans/s (by the stamps; "
                   "> 0, a rate at or above the log's own keeps every scan)")
    p.add_argument("--max-scans", type=count(2), help="stop after this many scans (at least 2)")
    p.add_argument("--quiet", "--no-progress", dest="quiet", action="store_true", help="no progress bar")
    add_log_options(p)
    p.set_defaults(func=run)


def _extractor_fields_hint(nested: bool) -> str:
    """How to set an extractor's fields, in a run's config.yaml (``nested``: under slam:) or a mapping of SLAM fields."""
    return (f"set extractor fields under {'slam: ' if nested else ''}extractor_params: (`extractor_params: {{k: 7}}`), "
            "or with --set extractor.FIELD=VALUE (extractor.METHOD.corners.FIELD=VALUE for a baseline's corner field)")


def _check_extractor_record(config: Path, recorded: dict, cfg: Any) -> None:  # noqa: ANN401 - a SlamConfig
    """InputError for a run's config.yaml whose ``extractor_config:`` record (the extractor's resolved
    settings, :func:`experiments.slamrun.write_config`) differs from what its ``slam:`` section gives
    (``extractor`` with ``extractor_params``) in a field that ``extractor_params`` does not set: an edit of
    the record, which ``--config`` does not read (`k: 3` -> `k: 7` there ran k = 3, exit 0, the record of
    the new run saying 3), or the record of an older version whose defaults differ (the run would not
    be the recorded one). Not checked: a field ``slam: extractor_params`` sets (the edit that is read;
    the record is then of the run before it), a record of another method's fields (``slam: extractor``
    edited), a field the record lacks; a mode-bound noise field recorded as ``"V: not read (no
    MODE-mode scan)"`` matches V."""
    import dataclasses

    from experiments.compare import resolved_configs
    from experiments.overrides import MODE_FIELDS
    from features.registry import get_method
    from lms200.yamlio import dump as dump_yaml

    def fields_of(method: str) -> set[str]:  # the names of a method's config fields
        return {f.name for f in dataclasses.fields(get_method(method).config_type)}

    try:
        own = fields_of(cfg.extractor)
        resolved = resolved_configs([cfg.extractor], {cfg.extractor: cfg.extractor_params})[cfg.extractor]
    except Exception:  # noqa: BLE001 - the run checks its extractor's fields itself, with its own message
        return
    if not set(recorded) <= own:  # another method's record (slam: extractor was changed: the edit that is read)?
        from features.registry import available_methods

        others = [fields_of(m) for m in available_methods()]
        if any(set(recorded) <= fields for fields in others):
            return
        field = sorted(set(recorded) - own, key=str)[0]
        raise InputError(f"{config}: extractor_config: {field}: {recorded[field]!r} is a field of no extractor (nor "
                         f"of {cfg.extractor}, which its slam: section names): an edit of the record of what a run ran, "
                         f"which --config does not read; delete it, or {_extractor_fields_hint(True)}")
    expected = load_yaml(dump_yaml(resolved))  # as the record was written and read back: tuples as lists

    def differs(path: str, got: Any, want: Any, raw: Any) -> tuple[str, Any, Any] | None:  # noqa: ANN401
        if isinstance(got, dict) and isinstance(want, dict):
            for key, value in got.items():
                if key not in want:
                    return f"{path}{key}", value, None
                found = differs(f"{path}{key}.", value, want[key], raw.get(key) if isinstance(raw, dict) else None)
                if found:
                    return found
            return None
        if got == want:
            return None
        field = path.rstrip(".")
        if field in MODE_FIELDS and isinstance(got, str) and got.startswith(f"{raw!r}: not read ("):
            return None
        return field, got, want

    unset = {k: v for k, v in recorded.items() if k not in cfg.extractor_params}
    found = differs("", unset, expected, resolved)
    if found is None:
        return
    from features.registry import available_methods

    for method in available_methods():  # a record of another method of the same fields (split_merge / iepf)?
        if method == cfg.extractor or fields_of(method) != own:
            continue
        try:
            theirs = resolved_configs([method], {method: cfg.extractor_params})[method]
        except Exception:  # noqa: BLE001 - the params may not suit that method: not its record then
            continue
        if differs("", unset, load_yaml(dump_yaml(theirs)), theirs) is None:
            return  # slam: extractor was changed (the edit that is read); the record is the earlier method's
    field, got, want = found
    gives = f"has no field {field.rpartition('.')[2]!r} there" if want is None else f"gives {want!r}"
    raise InputError(f"{config}: extractor_config: {field}: {got!r}, where its slam: section ({cfg.extractor}) {gives}: "
                     "extractor_config: is the record of what a run ran, which --config does not read, so an edit there "
                     "would be ignored, and a record of another lmsbench version's defaults would not be reproduced; "
                     f"delete extractor_config: to run what slam: gives, or {_extractor_fields_hint(True)}")


def _config(args: argparse.Namespace):
    import dataclasses

    import yaml

    from lms200 import LmsbenchError
    from slam import SlamConfig

    from experiments.user_methods import ensure_method, is_user_method

    cfg = SlamConfig()
    if args.config:
        check_yaml(args.config, "a SLAM config.yaml")
        try:
            raw = load_yaml(args.config.read_text())
        except yaml.YAMLError as exc:
            raise LmsbenchError(f"{args.config}: not valid YAML ({exc})") from None
        if raw is None:  # ran the defaults silently (a file saved empty); simulate and sweep refused theirs
            raise InputError(f"{args.config}: no SLAM config field in it (empty, or comments only); give the fields "
                             "to change (`{}` for none), or leave --config out for the defaults")
        if not isinstance(raw, dict):
            raise LmsbenchError(f"{args.config}: expected a mapping of SLAM config fields")
        if "slam" in raw:  # a run's config.yaml: {input: ..., slam: {...}}
            # a run's records of what ran (extractor_config:, versions:) are not settings: read past
            beside = sorted(str(k) for k in raw if k not in ("slam", "input", *SLAM_RECORD_KEYS))
            if beside:  # they were ignored: `motion: {sigma_accel: 9}` beside `slam:` ran with 1.0
                raise InputError(f"{args.config}: key(s) {beside} beside the slam: section would be ignored; "
                                 "put them under slam:")
            if not isinstance(raw["slam"], dict):
                raise InputError(f"{args.config}: slam: must be a mapping of SLAM config fields, got {raw['slam']!r}")
        fields = raw.get("slam", raw)
        if "extractor_config" in fields:  # refused as an unknown field, without saying where extractor fields go
            where = "under slam:" if "slam" in raw else "in it"
            raise InputError(f"{args.config}: extractor_config: {where} is no SLAM config field (a slam run's config.yaml "
                             "records the extractor's resolved settings under that name, beside slam:, and --config does "
                             f"not read them); {_extractor_fields_hint('slam' in raw)}")
        try:
            if isinstance(fields.get("extractor"), str) and is_user_method(fields["extractor"]):
                ensure_method(fields["extractor"])  # registered before SlamConfig checks the name
            cfg = SlamConfig.from_dict(fields)
        except LmsbenchError as exc:
            raise InputError(f"{args.config}: {exc}") from None
        if "slam" in raw and isinstance(raw.get("extractor_config"), dict):
            _check_extractor_record(args.config, raw["extractor_config"], cfg)
    changes = {}
    if args.preset:
        changes["preset"] = args.preset
    if args.extractor is not None:
        if "," in args.extractor:
            raise InputError(f"--extractor {args.extractor}: one extractor runs in the SLAM; give one name")
        changes["extractor"] = check_methods([args.extractor])[0]
    if args.association:
        changes["association"] = dataclasses.replace(cfg.association, method=args.association)
    if args.corners:
        changes["observations"] = dataclasses.replace(cfg.observations, use_corners=True)
    if args.odometry:
        changes["motion"] = dataclasses.replace(cfg.motion, use_odometry=True)
    try:  # --extractor with the file's extractor_params: SlamConfig checks them against the method
        cfg = dataclasses.replace(cfg, **changes)
    except LmsbenchError as exc:
        raise InputError(f"{args.config}: {exc}" if args.config else str(exc)) from None
    if args.params:  # --set extractor.FIELD=VALUE: compare's and the sweeps' spelling, into extractor_params
        check_set_once(args.params)
        overrides = extractor_overrides(dict(args.params), [cfg.extractor])[cfg.extractor]
        try:
            cfg = dataclasses.replace(cfg, extractor_params={**cfg.extractor_params, **overrides})
        except LmsbenchError as exc:
            raise InputError(f"--set: {exc}") from None
    if cfg.motion.use_odometry and args.no_odometry_baseline:  # it set nothing: the run itself uses the odometry
        raise InputError("--no-odometry-baseline: this run uses the odometry itself, so there is no separate "
                         "odometry baseline to leave out (--no-paper-baseline leaves out the paper preset's run)")
    if cfg.preset == "paper" and args.no_paper_baseline:  # it set nothing: `slam RUN --preset paper --no-paper-baseline` ran, exit 0
        raise InputError("--no-paper-baseline: this run is the paper preset itself, so there is no separate paper "
                         "baseline to leave out (--no-odometry-baseline leaves out the run driven by the odometry)")
    if cfg.preset == "paper":  # no run of it is the default pipeline (nor any baseline): its sections unread
        _refuse_unread_sections(cfg, DEFAULT_ONLY_SECTIONS, args.config,
                                "the default pipeline, which --preset paper does not run (its baselines are the paper "
                                "preset's too): drop them, or run the default preset")
    elif args.no_paper_baseline and (args.no_odometry_baseline or cfg.motion.use_odometry):
        # with the default preset, --association / --corners and the paper-only sections set the paper preset's
        # baselines (its run and, without --odometry, the odometry one): unread only when neither runs
        odometry = "--no-odometry-baseline" if args.no_odometry_baseline else "--odometry, which has no separate odometry baseline"
        _refuse_paper_settings(args, cfg, f"the default pipeline, with --no-paper-baseline and {odometry}")
    return cfg


#: the SlamConfig sections only the default pipeline reads, and only the paper preset's filter (docs/slam.md's table)
DEFAULT_ONLY_SECTIONS = ("alignment", "keyframes", "loop_closure")
PAPER_ONLY_SECTIONS = ("association", "landmarks", "prealign")


def _refuse_paper_settings(args: argparse.Namespace, cfg: "SlamConfig", why: str) -> None:
    """InputError for --association / --corners, or a --config field of the paper preset's own sections
    (PAPER_ONLY_SECTIONS), where no run of the command reads the paper preset's filter; ``why``: the
    run that does run, said in parentheses. Checked from the options, and again once the input is read
    (an input without odometry on every scan runs no odometry baseline)."""
    paper_only = [flag for flag, given in (("--association", args.association), ("--corners", args.corners)) if given]
    what = f"the paper preset's filter, which this run does not use ({why}): add --preset paper or drop them"
    if paper_only:
        raise InputError(f"{', '.join(paper_only)} set {what}")
    _refuse_unread_sections(cfg, PAPER_ONLY_SECTIONS, args.config, what)


def _odometry_lack(data: Any) -> str:
    """How an input (``data.records``) lacks the odometry on every scan that an odometry baseline needs."""
    missing = data.records.missing_odometry()
    return "has no odometry" if missing == len(data.records) else f"has none on {missing} of its {len(data.records)} scans"


def _refuse_unread_sections(cfg: "SlamConfig", sections: tuple[str, ...], where: Path | None, what: str) -> None:
    """InputError naming the fields of ``sections`` that ``cfg`` sets to other than their defaults (a --config
    file's), which no run of this command reads: `slam RUN --config C --preset paper` with C's
    `loop_closure: {every: 5}` ran, exit 0, and wrote the unread setting into config.yaml as if it had run
    (round 7). An earlier run's config.yaml, every section at its defaults but the ones set, is taken."""
    import dataclasses

    from slam import SlamConfig

    defaults = SlamConfig()
    changed = [f"{section}.{f.name}" for section in sections for f in dataclasses.fields(getattr(cfg, section))
               if getattr(getattr(cfg, section), f.name) != getattr(getattr(defaults, section), f.name)]
    if changed:
        shown = ", ".join(changed[:3]) + (f" and {len(changed) - 3} more" if len(changed) > 3 else "")
        raise InputError(f"{where}: {shown} set{'s' if len(changed) == 1 else ''} {what}")


def _warn_unread(config: "SlamConfig", range_maxes: set[float], where: Any, said: list[str]) -> None:
    """A warning line per extractor field of the run (``extractor_params``: --config, --set) that no
    scan reads: ``sigma_r: 0.02`` (configs/slam-mit-csail.yaml) ran bit for bit as the defaults on
    the cm-mode MIT CSAIL log, whose scans read sigma_r_cm, and nothing said so. ``range_maxes``: the
    scans' range_max values (m)."""
    from features.registry import make_config

    from features.registry import unread_fields

    configs = {config.extractor: make_config(config.extractor, **config.extractor_params)}
    for line in unread_fields({config.extractor: config.extractor_params}, configs,
                              sorted(range_maxes), f"the scans of {Path(str(where)).name}"):
        said.append(f"lmsbench slam: warning: {line}")


def in_time_order(stamps: list[float]) -> list[int]:
    """Indices of the longest run of scans, in log order, whose stamps (s) never decrease: the
    fewest scans dropped to leave the rest in time order (a stamp that jumps ahead costs that one
    scan, not every scan after it). O(n log n)."""
    tails: list[float] = []  # tails[j]: the least last stamp of a kept run of length j + 1
    tail_at: list[int] = []  # its scan index
    before = [-1] * len(stamps)  # the scan kept before scan k in the longest run ending at k
    for k, t in enumerate(stamps):
        j = bisect.bisect_right(tails, t)
        if j == len(tails):
            tails.append(t)
            tail_at.append(k)
        else:
            tails[j], tail_at[j] = t, k
        before[k] = tail_at[j - 1] if j else -1
    keep, k = [], tail_at[-1] if tail_at else -1
    while k >= 0:
        keep.append(k)
        k = before[k]
    return keep[::-1]


def _check_input(path: Path) -> None:
    """A simulator folder (scans.clf), a ROS 2 bag folder, or a log file of a known kind."""
    check_simulate_finished(path)  # first: a killed run's folder may hold no scans.clf ("no such input")
    if not path.exists():
        raise InputError(missing_message(path, "input"))  # "X: no such input (did you mean X.gz?)"
    check_log(path)  # a simulate folder's scans.clf, a bag folder or a log file


def _not_lms200_shape(shapes: list[tuple[int, float]]) -> str | None:
    """The first scan shape of ``shapes`` (beams, angle_increment rad: the scans', each once, in the order
    met) that no LMS200 takes (``lms200.timing.lms200_shaped``), described ("1081 beams at 0.25 deg over
    270 deg"), or None."""
    from lms200.timing import lms200_shaped

    for n, inc in shapes:
        if not lms200_shaped(n, inc):
            deg = np.degrees(inc)
            return f"{n} beams at {deg:.4g} deg over {(n - 1) * deg:.4g} deg"
    return None


def run(args: argparse.Namespace) -> int:
    from lms200 import LmsbenchError

    from experiments.slamrun import (deskew_for_sensor, load_input, run as run_slam, simulated_interlaced,
                                     write_scores)

    from experiments.slamrun import EVERY_AND_RATE

    started = time.perf_counter()  # the whole command's wall clock, which the summary says beside the run's own
    # the checks' notes and warnings are said once they pass: a refused run is its error alone (`slam LOG
    # --odometry` on a log whose steps take no time said that warning, then the odometry's error)
    with said_after_checks() as said:
        if args.every != 1 and args.rate_hz is not None:  # before any work, as load_input refuses them too
            raise LmsbenchError(EVERY_AND_RATE.format(every=args.every, rate_hz=args.rate_hz))
        _check_input(Path(args.input))
        if args.relations is not None:
            check_file(args.relations, "a relations file")
        # `slam RUN --config DIR/config.yaml --out DIR` wrote the resolved settings over the given file
        # (a simulate folder as --out holds its scans.clf, which check_out refuses by name)
        check_out_spares(args.out, SLAM_OUTPUTS, [f for f in (args.input, args.config, args.relations) if f is not None])
        # by name alone a folder of the user's metrics.json and slam.png passed, and the run deleted them
        check_out(args.out, writes=SLAM_OUTPUTS, owner=SLAM_OWNER)  # after: an input in --out is the sharper message
        config = _config(args)
        interlaced = simulated_interlaced(args.input)  # before the read: a config.yaml whose interlaced is no bool is refused
        data = load_input(args.input, args.relations, args.every, args.max_scans, args.rate_hz,
                          read_options=read_log_options(args), config=config)
        for note in data.notes:
            said.append(note)
        _warn_unread(config, data.records.range_maxes(), data.sources.get("scans", args.input), said)
        stamps = data.stamps.tolist()
        back = next((k for k in range(1, len(stamps)) if stamps[k] < stamps[k - 1]), None)
        if back is not None:
            where = data.sources.get("scans", args.input)
            if not args.skip_bad_lines:
                raise InputError(f"{where}: time goes backwards at scan {data.number(back)} (stamp {fixed(stamps[back])} s "
                                 f"after {fixed(stamps[back - 1])} s); SLAM needs scans in time order (--skip-bad-lines "
                                 "skips the fewest scans that leave the rest in order)")
            keep = in_time_order(stamps)
            kept = set(keep)
            for k in (k for k in range(len(stamps)) if k not in kept):
                said.append(f"{where}: skipped scan {data.number(k)} (stamp {fixed(stamps[k])} s): out of time order")
            data.records = data.records.taken(keep)
            if data.truth is not None and np.array_equal(data.truth[:, 0], stamps):  # a pose per scan (TRUEPOS)
                data.truth = data.truth[keep]
            if len(data.records) < 2:  # it ran on the one scan left (load_input refuses a one-scan input)
                raise InputError(f"{where}: {len(data.records)} of its {len(stamps)} scans are in time order; SLAM "
                                 "needs two or more")
        from slam.run import in_scale

        # before any output (run_slam checks the same as it goes: a stamp 1e200 s after the one before or an
        # odometry of 1e300 m was an internal error after the run started)
        for _ in in_scale(data.records.light(), f"{data.sources.get('scans', args.input)}: scan {{k}}", data.numbers):
            pass
        stamps = data.stamps.tolist()
        still = [k for k in range(1, len(stamps)) if stamps[k] == stamps[k - 1]]
        if still:  # each such step predicts no motion and searches no turn: kept (a coarse clock still works), said
            over = ("the motion model predicts no motion and the search no turn over them" if not config.motion.use_odometry
                    else "where the odometry gives no step for them, the motion model predicts no motion and the search no "
                         "turn over them")
            said.append(f"lmsbench slam: warning: {data.sources.get('scans', args.input)}: {len(still)} of {len(stamps) - 1} "
                  f"steps take no time (scan {data.number(still[0])} has the stamp of the scan kept before it, scan "
                  f"{data.number(still[0] - 1)}'s {fixed(stamps[still[0]])} s): "
                  f"{over}")
        gaps = [k for k in range(1, len(stamps)) if stamps[k] - stamps[k - 1] > config.motion.max_gap]
        if gaps:  # the constant-velocity model knows nothing of such a gap: the motion restarts (slam.config.MotionConfig)
            longest = max(gaps, key=lambda k: stamps[k] - stamps[k - 1])
            over = "" if not config.motion.use_odometry else " where the odometry gives no step"
            said.append(f"lmsbench slam: warning: {data.sources.get('scans', args.input)}: {len(gaps)} of {len(stamps) - 1} "
                  f"steps are longer than motion.max_gap, {config.motion.max_gap:g} s (scan {data.number(longest)} is stamped "
                  f"{stamps[longest] - stamps[longest - 1]:.6g} s after scan {data.number(longest - 1)}, the one kept before "
                  f"it): the motion restarts{over} from the "
                  "last pose with zero velocity after each")
        if config.motion.use_odometry and data.odometry is None:
            asked = "--odometry" if args.odometry else f"motion.use_odometry (in {args.config})"
            missing = data.records.missing_odometry()
            has = "this input has none" if missing == len(data.records) else f"{missing} of the {len(data.records)} scans have none"
            raise LmsbenchError(f"{args.input}: {asked} needs odometry on every scan, and {has}")
        if args.no_odometry_baseline and data.odometry is None:  # it set nothing: the baseline runs only with odometry
            raise InputError(f"--no-odometry-baseline: {args.input} {_odometry_lack(data)}, so there is no odometry "
                             "baseline to leave out (it runs only on an input with odometry on every scan)")
        if config.preset == "default" and args.no_paper_baseline and data.odometry is None:
            # the paper preset's filter runs in no baseline: not the paper one (left out), nor the odometry one (no
            # odometry on this input); the option check could not know the input (review of round 7)
            _refuse_paper_settings(args, config, f"the default pipeline, with --no-paper-baseline, on {args.input}, which "
                                                 f"{_odometry_lack(data)} for an odometry baseline")
    if interlaced is False and config.preset == "default" and config.alignment.deskew:
        config = deskew_for_sensor(config, interlaced=False)
        print(f"{args.input}: simulated with interlaced=False (every beam from one pose): alignment.deskew off",
              file=sys.stderr)
    odd = _not_lms200_shape(data.records.shapes_in_order()) if config.preset == "default" and config.alignment.deskew else None
    import dataclasses

    from slam.config import MAX_BEAM_TIME_INCREMENT_S

    given = data.time_increment  # a bag's LaserScans' own time_increment
    if odd is not None and config.alignment.beam_time_increment == 0 and given is not None \
            and given <= MAX_BEAM_TIME_INCREMENT_S:
        config = dataclasses.replace(config, alignment=dataclasses.replace(config.alignment, beam_time_increment=given))
        print(f"{data.sources.get('scans', args.input)}: {odd}, which no LMS200 takes: de-skewed with the bag's "
              f"time_increment, {given * 1e6:.4g} us between beams (alignment.beam_time_increment)", file=sys.stderr)
    elif odd is not None and config.alignment.beam_time_increment == 0:
        config = deskew_for_sensor(config, interlaced=False)
        print(f"{data.sources.get('scans', args.input)}: {odd}, which no LMS200 takes: its beam timing is unknown, "
              "alignment.deskew off (set alignment.beam_time_increment, s between beams, to de-skew it)",
              file=sys.stderr)
    from experiments.progress import warm_up_kernels

    warm_up_kernels(slam=config.preset == "default")
    import warnings

    from features.registry import UnreadNoiseWarning

    with warnings.catch_warnings():  # said above, before the run (_warn_unread), not again by each run_slam of it
        warnings.simplefilter("ignore", UnreadNoiseWarning)
        result = run_slam(data, config, progress=not args.quiet, odometry_baseline=not args.no_odometry_baseline,
                          out=args.out, paper_baseline=not args.no_paper_baseline, replace_earlier=True)
    write_scores(args.out, data, result)  # run() wrote config.yaml, the trajectory and the map
    args.outputs_complete = True  # a reader of stdout that goes away now leaves them whole (cli._stdout_gone)
    m = result.metrics
    # 'in 58.1 s (35 scans/s of CPU time)' read as one clock: 906 / 58.1 is 15.6 (the wall clock holds the baselines too)
    # and '1988 scans in 6.2 s' read as the command's time, which was 85 s with the baselines (a researcher's
    # walkthrough): the time is the run's own SLAM's, said so, and the whole command's follows
    print(f"slam ({config.preset} preset): {m['n_scans']} scans in {m['seconds']:.1f} s of wall-clock time "
          f"({m['cpu_scans_per_s']:.0f} scans/s of CPU time) for this run's own SLAM, {m['landmarks']['lines']} "
          f"map lines; outputs in {args.out}")
    print("  " + _time_line(m, time.perf_counter() - started))
    if "loop_closures" in m:
        lc, t0 = m["loop_closures"], float(data.stamps[0])
        shown = ", ".join(f"{fixed(c['new_stamp'] - t0, 1)} s -> {fixed(c['old_stamp'] - t0, 1)} s" for c in lc["closed"][:6])
        more = ", ..." if lc["n"] > 6 else ""
        print(f"  {lc['n']} loop closures over {lc['n_keyframes']} keyframes" + (f" ({shown}{more})" if lc["n"] else ""))
    for line in _score_lines(m):
        print(line)
    warning = _health_warning(m, config)
    if warning:
        print(f"lmsbench slam: warning: {args.input}: {warning}", file=sys.stderr)
    scored = m.get("ate", {}).get("n")
    if scored is not None and scored < 0.9 * m["n_scans"]:  # the reference's span: poses outside it are left out
        print(f"lmsbench slam: warning: {args.input}: the ATE covers {scored} of the run's {m['n_scans']} poses, those "
              f"within the span of its reference ({m.get('reference', 'ground truth')}); the rest are not scored "
              "(metrics.json ate.n)", file=sys.stderr)
    rel = m.get("relations", {})
    listed = int(rel.get("n", 0)) + int(rel.get("n_skipped", 0))
    if listed and rel.get("n", 0) < 0.9 * listed:  # --max-scans 100 on MIT CSAIL scored 24 of 1172, beside the published
        print(f"lmsbench slam: warning: {args.input}: the relations error covers {rel.get('n', 0)} of the file's "
              f"{listed} relations, those within the run's time span (--max-scans or a cut log leave the rest "
              "out); it is not comparable with errors over the whole log (metrics.json relations.n, n_skipped)",
              file=sys.stderr)
    used = m["consistency"].get("odometry_fraction")
    if used is not None and used < 0.9:  # steps beyond what the search could check fell back to the motion model
        steps = max(int(m["n_scans"]) - 1, 1)
        print(f"lmsbench slam: warning: {args.input}: the odometry predicted only {round(used * steps)} of {steps} "
              f"steps ({100 * used:.1f} %); the others used the constant-velocity model (a step longer than the scan's "
              f"reach, or whose {config.alignment.search_sigmas:g} std (motion.odom_noise) exceed the search's "
              f"{config.alignment.search_xy:g} m window: "
              "metrics.json consistency.odometry_fraction)", file=sys.stderr)
    if "note" in m.get("relations", {}):
        print(f"  relations: {m['relations']['note']}")
    if "anchors_relations_trans_mean_m" in m:
        print("  published relations error (m): " + ", ".join(f"{k} {v}" for k, v in m["anchors_relations_trans_mean_m"].items()))
    return 0


def _time_line(m: dict[str, Any], total: float) -> str:
    """The whole command's wall-clock time, ``total`` s, and the share of each baseline SLAM
    (metrics.json's ``table`` rows after the first, with their ``seconds``)."""
    baselines = [f"{row['source']} {row['seconds']:.1f} s" for row in m.get("table", [])[1:]
                 if isinstance(row.get("seconds"), (int, float))]
    parts = [f"this run's SLAM {m['seconds']:.1f} s"]
    if baselines:
        parts.append("the baselines' " + ", ".join(baselines))
    return (f"the whole command took {total:.1f} s of wall-clock time ({'; '.join(parts)}; the rest reading "
            "the input, compiling or loading kernels, scoring and writing the outputs)")


def _score_lines(m: dict[str, Any]) -> list[str]:
    """This run's scores beside its baselines' (metrics.json's ``table``, this run first): the ATE
    against true poses (or a log's corrected poses, so named), the relations error against a
    relations file. The summary printed the
    published relations errors of MIT CSAIL with none of this run's."""
    lines = []
    ate_label = "ATE RMS (m)" if m.get("reference", "ground truth") == "ground truth" else \
        f"ATE RMS against the log's {m['reference']} (m)"
    rel = m.get("relations", {})
    far = (f"relations error over poses more than {rel.get('far_apart_s', 200):g} s apart, mean (m; "
           f"{rel.get('n_far', 0)} relations)")
    # the README's MIT CSAIL columns "median" and "> 200 s apart, mean" were in no output (a researcher's walkthrough)
    for key, label in (("ate_rmse", ate_label), ("relations_trans_mean", "relations error, mean (m)"),
                       ("relations_trans_median", "relations error, median (m)"), ("relations_trans_mean_far", far)):
        rows = [(("this run" if i == 0 else row["source"]), row[key]) for i, row in enumerate(m.get("table", []))
                if isinstance(row.get(key), (int, float)) and math.isfinite(row[key])]
        if rows and rows[0][0] == "this run":
            lines.append(f"  {label}: " + ", ".join(f"{source} {value:.3g}" for source, value in rows))
    if not lines and "ate" not in m and "relations" not in m:  # csail-robotlaser1 printed no score and said nothing of why
        lines.append("  no score: the input has no reference to score the run against (no true or corrected poses, "
                     "no relations file: --relations FILE, or NAME.relations beside the log)")
    return lines


def _health_warning(m: dict[str, Any], config: "SlamConfig") -> str:
    """The warning (one line, no prefix) for a run that is not healthy or diverged, naming every
    reason that holds; "" when there is none."""
    c = m["consistency"]
    reasons = _unhealthy_reasons(m, config)
    if not c["healthy"]:
        return (f"the run is not healthy: {'; '.join(reasons or ['the trajectory is not finite'])} "
                f"(metrics.json: consistency.healthy false)")
    return "; ".join(reasons)  # the paper preset stays healthy when its estimate diverged


def _unhealthy_reasons(m: dict[str, Any], config: "SlamConfig") -> list[str]:
    """Every reason ``m`` (metrics.json's mapping) gives against the run, one phrase each: a
    divergence, too few matched steps, too many ambiguous steps, a stretch of degenerate matches that may
    have drifted too far, a broken filter state."""
    c = m["consistency"]
    steps = max(int(m["n_scans"]) - 1, 1)
    cc = config.consistency
    out = []
    if c.get("diverged"):
        if config.preset == "paper":
            out.append(f"the estimate diverged at t={c['diverged_at']} (the filter's state broke, the mean NIS per "
                       f"dof over {cc.nis_window} scans exceeded {cc.nis_divergence:g}, or {cc.point_window} scans "
                       f"in a row put fewer than {cc.point_min_score:g} of their points on the map)")
        else:
            out.append(f"the estimate diverged at t={c['diverged_at']} ({cc.point_window} scans in a row put fewer "
                       f"than {cc.point_min_score:g} of their points on the map)")
    matched = c.get("matched_fraction")
    if matched is not None and matched < cc.min_matched_fraction:
        out.append(f"only {round(matched * steps)} of {steps} steps ({100 * matched:.1f} %) were matched to the map "
                   f"(the others are the motion model's guess; consistency.min_matched_fraction "
                   f"{cc.min_matched_fraction:g})")
    share = c.get("ambiguous_fraction")
    if share is not None and share > cc.max_ambiguous:
        out.append(f"{round(share * steps)} of {steps} steps ({100 * share:.1f} %) were ambiguous (a distinct pose "
                   f"fitted the scan as well and only the motion model chose; consistency.max_ambiguous "
                   f"{cc.max_ambiguous:g})")
    doubt = c.get("odometry_doubt_fraction")
    if doubt is not None and doubt > cc.max_odometry_doubt:
        # measured on Intel and ACES, whose odometry is right: in all 30 such steps the odometry's match was the
        # right one and the other had slid along a corridor (docs/slam.md), so the phrase names both causes
        out.append(f"{round(doubt * steps)} of {steps} steps ({100 * doubt:.1f} %) doubted the odometry (the match from "
                   f"its step explained under {config.alignment.retry_inliers:g} of the points and the constant-"
                   f"velocity prediction's clearly more: a wrong odometry, or matching that is ambiguous there, as "
                   f"along a corridor; consistency.max_odometry_doubt {cc.max_odometry_doubt:g})")
    drift = c.get("degenerate_drift")
    if drift is not None and cc.degenerate_stretch_flagged(drift):
        # the stamp is the scan where the stretch's sum peaked, not where the stretch ended
        out.append(f"a stretch of degenerate matches (the weakest direction held by fewer than "
                   f"{cc.degenerate_points:g} points' worth, as along a corridor) may have drifted {drift:.2f} m along "
                   f"its weak axis by t={c['degenerate_drift_at']} (the stds along it of its keyframes and of that "
                   f"scan, each at most its predictions', summed; "
                   f"consistency.max_degenerate_drift {cc.max_degenerate_drift:g} m)")
    if config.preset == "paper" and not c["healthy"]:
        out.append("the filter's state is not finite or its covariance is not positive definite")
    return out
