"""The fits' one-BLAS-thread limit holds inside the block and is lifted after it."""

import numpy as np
from threadpoolctl import threadpool_info

from fosmodel import FOSModel
from fosmodel.core import correlations
from fosmodel.core.blas import one_blas_thread


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_limit_inside_and_restored_after():
    before = _blas_threads()
    with one_blas_thread():
        assert set(_blas_threads()) == {1}
    assert _blas_threads() == before


def test_fit_runs_its_search_on_one_blas_thread(monkeypatch):
    seen = []
    column = correlations.LagCorrelations.column
    monkeypatch.setattr(correlations.LagCorrelations, "column",
                        lambda self, j: seen.append(_blas_threads()) or column(self, j))
    before = _blas_threads()
    y = np.random.default_rng(0).standard_normal(2000)
    FOSModel(max_lag=4, degree=2, stop="max_terms", max_terms=6).fit(y)
    assert seen and all(set(s) == {1} for s in seen)
    assert _blas_threads() == before
