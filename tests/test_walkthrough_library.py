"""A researcher's walkthrough of lmsbench as a Python library (README and docs/*.md alone, no
command line), 2026-12-05: what the docs said that the code did not do, one test each."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_features_page_states_the_iterator_cap_extract_many_applies() -> None:
    """docs/features.md said an iterator is read up to 92,948 scans of 361 beams (2^25 beams, the
    cap before a review raised it); the code's cap is 2^27 beams, 371,794 such scans."""
    from features import batch

    text = " ".join((ROOT / "docs" / "features.md").read_text().split())
    scans = batch.MAX_ITERATOR_BEAMS // 361
    assert scans == 371_794
    assert f"{scans:,} scans of 361" in text
    assert "92,948" not in text
