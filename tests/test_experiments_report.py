"""The demo report says what its timing table measures: each method's backend, from the table."""

from __future__ import annotations

import pandas as pd

from experiments.demo import method_table, timing_note
from features.registry import backend_of


def test_the_report_states_each_methods_backend_from_the_summary():
    methods = ["sensor", "split_merge", "iepf", "hough", "ransac"]
    summary = pd.DataFrame({"method": methods, "backend": [backend_of(m) for m in methods],
                            "time_ms_median": [0.07, 0.1, 0.09, 2.0, 3.0], "f1": [0.9, 0.8, 0.8, 0.7, 0.7]})
    shown = method_table(summary)
    assert list(shown.columns[:2]) == ["method", "backend"]
    assert dict(zip(shown["method"], shown["backend"])) == {m: backend_of(m) for m in methods}
    note = timing_note(summary)
    assert "Python + numpy" not in note
    if backend_of("sensor") == "numba":  # the default (backend="auto") where numba is installed
        assert "`sensor`, `split_merge`, `iepf` on numba-compiled kernels" in note
        assert "`hough`, `ransac` on vectorised numpy" in note
        assert "among `sensor`, `split_merge`, `iepf` compare compiled with compiled code" in note


def test_an_all_numpy_summary_says_so_and_claims_no_compiled_comparison():
    summary = pd.DataFrame({"method": ["sensor", "hough"], "backend": ["numpy", "numpy"]})
    note = timing_note(summary)
    assert "`sensor`, `hough` on vectorised numpy" in note and "compiled with compiled" not in note
    mixed = pd.DataFrame({"method": ["sensor", "hough"], "backend": ["numba", "numpy"]})
    assert "not like for like" in timing_note(mixed)
