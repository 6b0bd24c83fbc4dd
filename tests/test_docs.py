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
