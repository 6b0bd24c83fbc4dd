"""Benchmarks, one module per area, each with ``NAME: str`` and ``run(quick: bool) -> list[dict]``.

``lmsbench bench`` finds every module here and prints / saves the rows it returns (one dict per
measured case: what was measured, the rate, the unit). Benchmarks measure; tests never assert times.
"""
