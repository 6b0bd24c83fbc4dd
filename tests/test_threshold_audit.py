"""`python -m experiments.threshold_audit` (the README's audit command) reads its arguments before
its run (27 s, 2026-12-04): `--help` was taken for a world name (a traceback, "unknown world '--help'")."""

from __future__ import annotations

import pytest

from experiments import threshold_audit


def test_help_prints_the_usage_without_running(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(threshold_audit, "run", lambda world: pytest.fail("ran the audit"))
    assert threshold_audit.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: python -m experiments.threshold_audit [WORLD] [OUT.csv]\n") and "issue #13" in out


@pytest.mark.parametrize("argv, message", [
    (["offfice"], "threshold_audit: error: unknown world 'offfice'; known worlds: office, corridor,"),
    (["--bogus"], "threshold_audit: error: unrecognized arguments: --bogus"),
    (["office", "a.csv", "b"], "threshold_audit: error: unrecognized arguments: office a.csv b"),
])
def test_bad_arguments_are_one_error_line_before_any_run(argv: list[str], message: str, monkeypatch: pytest.MonkeyPatch,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(threshold_audit, "run", lambda world: pytest.fail("ran the audit"))
    assert threshold_audit.main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(message) and err[0].endswith("(see python -m experiments.threshold_audit --help)")
