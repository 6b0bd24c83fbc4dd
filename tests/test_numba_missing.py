"""numba is required: where it cannot be loaded, the first extraction says so in one clear error."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_a_missing_numba_is_a_clear_lmsbench_error() -> None:
    code = (
        "import sys; sys.modules['numba'] = None\n"  # makes `import numba` fail as if not installed
        "import numpy as np\n"
        "from features import extract\n"
        "from lms200 import LmsbenchError, Scan\n"
        "try:\n"
        "    extract(Scan.lms200(np.full(361, 2.0)))\n"
        "except LmsbenchError as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr[-1000:]
    assert out.stdout.startswith("NumbaUnavailableError")
    assert "numba" in out.stdout and "pip install" in out.stdout


def test_building_a_world_without_numba_is_the_same_clear_error() -> None:
    """The world generator (sim.nearest) and the ray caster (sim.hits) compile with numba too: without
    it, `make_world` raises the one-line NumbaUnavailableError, not a ModuleNotFoundError."""
    code = (
        "import sys; sys.modules['numba'] = None\n"
        "from lms200 import LmsbenchError\n"
        "try:\n"
        "    from sim import make_world\n"
        "    make_world('cluttered', 0)\n"
        "except LmsbenchError as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr[-1000:]
    assert out.stdout.startswith("NumbaUnavailableError") and "pip install" in out.stdout
