"""Every Python block of README.md and docs/*.md runs as written.

The blocks of one page run in order in one namespace (a later block may use what an earlier one
defined), in a temporary working folder, with matplotlib's Agg backend. A block that raises fails
the test with the page and the block's first line number.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, code) of every ```python block of a Markdown text."""
    return [(text.count("\n", 0, m.start(1)) + 1, m.group(1)) for m in FENCE.finditer(text)]


def test_blocks_are_found() -> None:
    blocks = python_blocks("a\n```python\nx = 1\n```\nb\n```python\ny = 2\n```\n")
    assert blocks == [(3, "x = 1\n"), (7, "y = 2\n")]
    assert python_blocks("```yaml\na: 1\n```\n") == []


def test_every_page_is_linked_from_the_readme() -> None:
    readme = (ROOT / "README.md").read_text()
    missing = [p.name for p in PAGES[1:] if f"docs/{p.name}" not in readme]
    assert not missing, f"docs pages not linked from README.md: {missing}"


def test_no_documented_command_writes_into_the_source_tree() -> None:
    """The README's tour said `lmsbench slam run --out slam`: run from the checkout, as the README
    is, it wrote trajectory.tum, map.json, ... into the slam package's own folder."""
    for page in PAGES:
        for out in re.findall(r"`lmsbench [^`]*--out ([^`\s\]]+)", page.read_text()):
            top = (ROOT / out).resolve()
            assert not (top.is_dir() and any(top.glob("*.py"))), f"{page.name}: --out {out} is a source folder"
            assert not (ROOT / out.split("/")[0]).is_dir() or out.split("/")[0] == "results", (page.name, out)


WITH_CODE = [p for p in PAGES if python_blocks(p.read_text())]


def test_the_tour_and_the_api_pages_have_code() -> None:
    assert {"README.md", "data.md", "simulator.md", "features.md", "lms200.md", "slam.md"} <= {p.name for p in WITH_CODE}


@pytest.mark.parametrize("page", WITH_CODE, ids=[p.name for p in WITH_CODE])
def test_python_blocks_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib

    from features import registry

    user = [n for n in registry._REGISTRY if ":" in n]

    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    blocks = python_blocks(page.read_text())
    namespace: dict = {"__name__": f"doc_{page.stem}"}
    try:
        for line, code in blocks:
            try:
                exec(compile(code, f"{page.name}:{line}", "exec"), namespace)
            except Exception as exc:  # noqa: BLE001 - reported with its place in the page
                pytest.fail(f"{page.relative_to(ROOT)}, block at line {line}: {type(exc).__name__}: {exc}")
    finally:  # a page's own MODULE:FUNCTION extractors do not stay registered for other tests
        for name in [n for n in registry._REGISTRY if ":" in n and n not in user]:
            del registry._REGISTRY[name]


#: options each command refuses together (experiments.commands: "--workers sets the processes of the
#: local cluster", "--inprocess runs the demo's sweep ...; --no-sweep skips it", "... that --tables replaces")
REFUSED_TOGETHER = {
    "sweep": [("--scheduler", "--inprocess"), ("--inprocess", "--workers"), ("--scheduler", "--workers")],
    "demo": [("--no-sweep", "--inprocess")],
    "figures": [("--tables", flag) for flag in ("--duration", "--rate-hz", "--seed", "--world", "--methods", "--intel",
                                                 "--no-slam")],
}


def test_the_experiments_pages_usage_lines_match_the_parser() -> None:
    """docs/experiments.md showed `sweep ... [--local] [--workers 2]`, two options the command
    refuses together, as if they went together. Each usage line's options are the command's own,
    and options refused together are written as alternatives (`A | B`)."""
    from experiments.cli import build_parser

    commands = next(a for a in build_parser()._actions if a.dest == "command").choices
    rows = [line for line in (ROOT / "docs" / "experiments.md").read_text().splitlines() if line.startswith("| `lmsbench ")]
    assert {row.split()[2] for row in rows} == set(REFUSED_TOGETHER)
    for row in rows:
        usage = row.split("`")[1]
        name = usage.split()[1]
        known = set(commands[name]._option_string_actions)
        flags = re.findall(r"--[a-z][a-z0-9-]*", usage)
        assert set(flags) <= known, (name, set(flags) - known)
        for a, b in REFUSED_TOGETHER[name]:
            if a in flags and b in flags:
                between = usage[min(usage.index(a), usage.index(b)):max(usage.index(a), usage.index(b))]
                assert "|" in between, f"{name}: {a} and {b} are refused together; the usage line shows them apart: {usage}"


def _options_with_defaults(parser, name=""):
    """(command, option, default, help) of every option of every (sub)command whose default is a value."""
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub, subparser in action.choices.items():
                yield from _options_with_defaults(subparser, f"{name} {sub}".strip())
        elif action.option_strings and action.default not in (None, False, [], argparse.SUPPRESS):
            yield name, action.option_strings[0], action.default, action.help or ""


def test_every_option_with_a_default_says_it_in_its_help() -> None:
    """`lmsbench demo --help` said `--seed SEED  world and run seed` and `figures --help` the same
    option with `(default 0)`; `lms200 record --timeout`, `--baud`, `compare --format`, `slam --every`
    did not say theirs either. Every option with a default value now names it in its help."""
    from experiments.cli import build_parser

    silent = [(cmd, opt, default) for cmd, opt, default, text in _options_with_defaults(build_parser())
              if "default" not in text]
    assert not silent, f"options whose help does not say their default: {silent}"


def test_every_simulate_option_with_a_default_says_it_in_its_help() -> None:
    """`lmsbench simulate --help` said `--seed SEED  seed of the world, tour and sensor noise (>= 0)`
    and nothing of its default, 0: simulate's options default to None in the parser (a --config
    run refuses them beside it) and take `experiments.commands.simulate.DEFAULTS` after."""
    from experiments.cli import build_parser
    from experiments.commands.simulate import DEFAULTS

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices["simulate"]
    helps = {a.dest: a.help or "" for a in sub._actions}
    said = {name: f"default {value:g}" if isinstance(value, float) else f"default {value}" for name, value in DEFAULTS.items()}
    silent = {name: text for name, text in said.items() if text not in helps[name]}
    assert not silent, f"simulate options whose help does not say their default: {silent}"


def test_the_figures_help_names_every_paper_figure_it_draws() -> None:
    """`lmsbench --help` said figures draws "the paper's figures (4-7, 9, 10)"; it draws fig3_scan too."""
    from experiments.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    summary = next(c.help for c in sub._choices_actions if c.dest == "figures")
    assert "(3-7, 9, 10)" in summary


@pytest.mark.parametrize("command", ["info", "calibrate", "sim2real"])
def test_the_log_argument_names_every_compression_that_is_read(command: str) -> None:
    """`lmsbench info --help` said a log is "CARMEN log (plain or .gz)", though the README and
    docs/data.md say, and `info LOG.bz2` / `info LOG.xz` show, that bzip2 and xz logs are read too."""
    from experiments.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices[command]
    log = next(a for a in sub._actions if a.dest == "log")
    assert ".gz" in log.help and ".bz2" in log.help and ".xz" in log.help


#: documented command lines that show an option the command refuses, on purpose (the error's example)
REFUSED_EXAMPLES = {("lms200 emulate", "--max-scans")}


def test_every_documented_command_line_names_options_its_command_has() -> None:
    """Every `lmsbench CMD ...` of README.md and docs/ (in backticks, or an indented or fenced
    command line) names a command of the parser and only options of that command, so a renamed or
    removed option cannot stay in the documentation."""
    import argparse

    from experiments.cli import build_parser

    commands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    wrong, seen = [], 0
    for page in PAGES:
        text = page.read_text()
        for m in re.finditer(r"(?:`|^\s*)lmsbench ([a-z][^`\n]*)", text, re.M):
            words = m.group(1).split()
            parser, name = commands.get(words[0]), words[0]
            if parser is None:  # a message quoted (`lmsbench compare: error: ...`), else no such command
                if not words[0].endswith(":"):
                    wrong.append(f"{page.name}:{text.count(chr(10), 0, m.start()) + 1}: no command {words[0]!r}")
                continue
            if name == "lms200" and len(words) > 1 and words[1] in ("emulate", "record"):
                sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
                parser, name = sub[words[1]], f"lms200 {words[1]}"
            seen += 1
            for flag in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)(?![a-z0-9*-])", m.group(1)):
                if flag not in parser._option_string_actions and (name, flag) not in REFUSED_EXAMPLES:
                    line = text.count("\n", 0, m.start()) + 1
                    wrong.append(f"{page.name}:{line}: lmsbench {name} has no option {flag}")
    assert seen > 100 and not wrong, wrong


def test_every_option_of_every_command_is_documented() -> None:
    """Each option string of every command and subcommand (`lmsbench COMMAND --help`) appears in
    README.md or docs/, where a user looks for what it does."""
    text = "\n".join(page.read_text() for page in PAGES)
    from experiments.cli import build_parser

    import argparse

    def options(parser, name=""):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub, subparser in action.choices.items():
                    yield from options(subparser, f"{name} {sub}".strip())
            else:
                yield from ((name, o) for o in action.option_strings if o.startswith("--") and o != "--help")

    found = list(options(build_parser()))
    missing = [(cmd, o) for cmd, o in found if not re.search(re.escape(o) + r"(?![a-z0-9-])", text)]
    assert len(found) > 150 and not missing, missing


def _default_rows(page: str, header: str):
    """(field names, default cell) of each row of the table under ``header`` in docs/``page``."""
    text = (ROOT / "docs" / page).read_text()
    block = text[text.index(header):]
    block = block[:block.index("\n\n")]
    for line in block.splitlines():
        m = re.match(r"^\| ((?:`[a-z0-9_]+`(?:, )?)+) \| ([^|]+) \|", line)
        if m:
            yield re.findall(r"`([a-z0-9_]+)`", m.group(1)), m.group(2)


def _same_default(cell: str, value) -> bool:
    """Whether a default as the docs write it (`0.005 m`, `"mm"`, `true`, `null`, `4 beams`) is ``value``."""
    if cell in ("true", "True", "false", "False"):
        return value is (cell.lower() == "true")
    if cell == "null":
        return value is None
    if cell.startswith('"'):
        return cell.strip('"') == value
    try:
        return abs(float(cell) - float(value)) <= 1e-6 * max(1.0, abs(float(value)))
    except (TypeError, ValueError):
        return False


@pytest.mark.parametrize("page, header, config", [
    ("features.md", "| name | default | meaning |", "features.sensor:SensorMethodConfig"),
    ("simulator.md", "| field | default | meaning |", "sim:SensorConfig"),
])
def test_the_parameter_tables_give_the_configs_defaults(page: str, header: str, config: str) -> None:
    """Each row of the docs' tables of `SensorMethodConfig` and `SensorConfig` fields states the
    field's default (several fields a row, their defaults comma-separated, units and notes in
    parentheses after them), and every field of the config has its row."""
    import dataclasses
    import importlib

    module, _, name = config.partition(":")
    cls = getattr(importlib.import_module(module), name)
    cfg, seen, wrong = cls(), set(), []
    for names, cell in _default_rows(page, header):
        cells = [part.strip().split()[0].strip("`") for part in re.sub(r"\([^)]*\)", "", cell).split(",")]
        assert len(cells) == len(names), (page, names, cell)
        for field, text in zip(names, cells):
            seen.add(field)
            if not _same_default(text, getattr(cfg, field)):
                wrong.append(f"{page}: {field} {text} (the config's default is {getattr(cfg, field)!r})")
    assert not wrong, wrong
    assert seen == {f.name for f in dataclasses.fields(cls)}, f"{page}: fields without a row: {sorted({f.name for f in dataclasses.fields(cls)} - seen)}"


def test_the_docs_sweep_files_pass_the_sweeps_checks() -> None:
    """Every ```yaml block of the docs that is a sweep file (it has `kind:`) is read as one and its
    parameter names pass the kind's checks before any cell runs (`lmsbench sweep` would run it)."""
    import yaml

    from experiments.sweep import SweepSpec
    from experiments.sweep.runner import check_spec

    fence = re.compile(r"^```yaml[ \t]*\n(.*?)^```[ \t]*$", re.S | re.M)
    specs = [(page.name, m.group(1)) for page in PAGES for m in fence.finditer(page.read_text())]
    sweeps = [(name, text) for name, text in specs if re.search(r"^kind:", text, re.M)]
    assert sweeps, "no sweep file in the docs"
    for name, text in sweeps:
        data = yaml.safe_load(text)
        if "samples" in data:  # one draw names what every draw names (1024 cells took 4 s to check)
            data["samples"] = 1
        spec = SweepSpec.from_dict(data)
        check_spec(spec)
        assert spec.cells(), name


def test_the_out_folders_paragraph_gives_the_record_size_bounds() -> None:
    """A review: docs/commands.md's paragraph on --out folders said which records tell an earlier run's
    folder, but not how large a record is read back (options.MAX_RECORD_YAML_BYTES, MAX_RECORD_JSON_BYTES):
    it gives both, and they are the code's."""
    from experiments.options import MAX_RECORD_JSON_BYTES, MAX_RECORD_YAML_BYTES

    text = (ROOT / "docs" / "commands.md").read_text()
    paragraph = next(p for p in text.split("\n\n") if "(`experiments.options.Owner`)" in p)
    assert (f"at most {MAX_RECORD_YAML_BYTES >> 20} MiB (YAML" in paragraph
            and "`experiments.options.MAX_RECORD_YAML_BYTES`" in paragraph)
    assert f"or {MAX_RECORD_JSON_BYTES >> 20} MiB (JSON" in paragraph and "`MAX_RECORD_JSON_BYTES`" in paragraph


#: the reading options every command that reads a log takes (experiments.cli), written `[LOG OPTIONS]` in the
#: usage lines of docs/commands.md's table
LOG_OPTIONS = ("--topic", "--skip-bad-lines", "--laser-fov-deg", "--laser-resolution-deg", "--laser-angle-min-deg",
               "--laser-range-max")


def test_the_commands_table_usage_lines_name_every_option() -> None:
    """docs/commands.md's table showed `lmsbench slam INPUT --out DIR [--preset P] [--rate-hz HZ] [--set ...]`,
    without --config, --extractor, --odometry, --relations, --every, --max-scans, ... of `slam --help`, and
    `sweep`, `figures`, `compare`, `simulate`, `demo` and `lms200 record` the same way. Each usage line of the
    table names every option of its command (one spelling of each; `LOG OPTIONS` for the log-reading ones),
    and only options the command has."""
    import argparse

    from experiments.cli import build_parser

    def subcommands(parser, name=""):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub, subparser in action.choices.items():
                    yield f"{name} {sub}".strip(), subparser
                    yield from subcommands(subparser, f"{name} {sub}".strip())

    parsers = dict(subcommands(build_parser()))
    rows = [line for line in (ROOT / "docs" / "commands.md").read_text().splitlines() if line.startswith("| `lmsbench ")]
    usages = [u for row in rows for u in re.findall(r"`(lmsbench [a-z][^`]*)`", row.split(" | ")[0])]
    seen, wrong = set(), []
    for usage in usages:
        words = usage.split()
        name = " ".join(words[1:3]) if words[1] == "lms200" else words[1]
        parser = parsers[name]
        seen.add(name)
        flags = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", usage))
        if "LOG OPTIONS" in usage:
            flags |= set(LOG_OPTIONS)
        spellings: dict[str, list[str]] = {}  # by dest: `compare --method` is `--methods` again
        for action in parser._actions:
            spellings.setdefault(action.dest, []).extend(o for o in action.option_strings if o.startswith("--") and o != "--help")
        wrong += [f"{name}: the usage line lacks {names[0]}" for names in spellings.values() if names and not flags & set(names)]
        wrong += [f"{name}: the usage line names {f}, which it does not have" for f in flags - set(parser._option_string_actions)]
    assert not wrong, wrong
    assert seen == {n for n, p in parsers.items() if n != "lms200"}, sorted(seen)
