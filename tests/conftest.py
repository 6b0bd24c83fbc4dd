"""Shared test fixtures: where the real logs are, and a skip when they are absent."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "carmen"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder of real CARMEN logs (../shared/data/carmen); skips the test where it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real logs not present at {SHARED_DATA} (only on the project's own machines)")
    return SHARED_DATA
