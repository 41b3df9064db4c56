"""fempipe.core.parallel.single_blas: the decorator form of single_blas_thread."""

from __future__ import annotations

from threadpoolctl import threadpool_info

from fempipe.core.parallel import single_blas


def _blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_single_blas_limits_the_call_and_keeps_the_function():
    @single_blas
    def inside(x, *, y=2):
        """Docstring."""
        return x + y, _blas_threads()

    import numpy as np  # noqa: F401  (BLAS loaded, so there is something to limit)

    before = _blas_threads()
    value, threads = inside(1, y=3)
    assert value == 4
    assert threads and all(t == 1 for t in threads)
    assert _blas_threads() == before
    assert inside.__name__ == "inside" and inside.__doc__ == "Docstring."
