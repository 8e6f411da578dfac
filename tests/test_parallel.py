"""Independent calls in worker processes give what the same calls give here."""

import operator

import pytest

from fosmodel.core.parallel import in_workers

CALLS = [(operator.pow, (base, 3)) for base in range(7)]
HERE = [base**3 for base in range(7)]


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_results_come_in_the_calls_order(n_jobs):
    assert list(in_workers(iter(CALLS), n_jobs)) == HERE


def test_unordered_results_are_the_same_results():
    assert sorted(in_workers(CALLS, 2, ordered=False)) == HERE
