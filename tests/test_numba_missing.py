"""numba is required: where it cannot be loaded, the first extraction, world or scan match says so
in one clear error."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("use", [
    "import numpy as np\nfrom features import extract\nfrom lms200 import Scan\nextract(Scan.lms200(np.full(361, 2.0)))\n",
    # the world generator (sim.nearest) and the ray caster (sim.hits) compile with numba too
    "from sim import make_world\nmake_world('cluttered', 0)\n",
    "import slam.icpkernel\n",
], ids=["extract", "make_world", "icp"])
def test_a_missing_numba_is_a_clear_lmsbench_error(use: str) -> None:
    code = (
        "import sys; sys.modules['numba'] = None\n"  # makes `import numba` fail as if not installed
        "from lms200 import LmsbenchError\n"
        "try:\n"
        + "".join("    " + line + "\n" for line in use.splitlines())
        + "except LmsbenchError as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr[-1000:]
    assert out.stdout.startswith("NumbaUnavailableError")
    assert "numba" in out.stdout and "pip install" in out.stdout


def test_numba_prints_no_colour_reset_on_a_terminal() -> None:
    """Defect: every command that compiles (simulate, slam, figures, sweep) wrote a stray "ESC[0m"
    after its last line on a terminal: numba's error highlighting (colorama, which evo requires)
    ran colorama.init() at the first compile, whose exit handler resets the terminal's colours."""
    import os
    import pty

    master, slave = pty.openpty()
    code = "from lms200.numba_required import numba\nprint(numba.njit(lambda x: x + 1)(1))\n"
    try:
        proc = subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, stdout=slave, stderr=slave,
                                env={k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING"})
        os.close(slave)
        shown = bytearray()
        try:
            while chunk := os.read(master, 4096):
                shown.extend(chunk)
        except OSError:  # EIO: the process has closed the terminal
            pass
        assert proc.wait(timeout=120) == 0
    finally:
        os.close(master)
    assert bytes(shown) == b"2\r\n"
