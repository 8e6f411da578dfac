"""Checks on in-memory signals: the messages name the signal and the sample."""

import numpy as np
import pandas as pd
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.core.validation import as_signal


def test_as_signal_takes_arrays_lists_and_series():
    for values in ([1, 2, 3], np.arange(1, 4), pd.Series([1.0, 2.0, 3.0])):
        out = as_signal(values, "y")
        assert out.dtype == float and out.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize("values, message", [
    ([[1.0, 2.0]], "y must be one-dimensional, got shape \\(1, 2\\)"),
    (["a", "b"], "y is not numeric"),
    ([1.0, np.nan, np.inf, 2.0], "y has 2 non-finite value.* first at sample 1"),
])
def test_as_signal_names_the_problem(values, message):
    with pytest.raises(InputError, match=message):
        as_signal(values, "y")


def test_last_checks_only_the_last_samples_and_names_the_absolute_sample():
    values = np.arange(10.0)
    values[2] = np.nan
    assert np.isnan(as_signal(values, "past", last=5)[2])  # outside the checked tail
    assert len(as_signal(values, "past", last=0)) == 10
    values[8] = np.inf
    with pytest.raises(InputError, match="past has 1 non-finite .* first at sample 8"):
        as_signal(values, "past", last=5)
    with pytest.raises(InputError, match="first at sample 2"):
        as_signal(values, "past", last=50)  # longer than the signal: all of it


def test_an_unpickled_record_passes_as_itself():
    # an array unpickled on a worker has an equal but distinct float64 dtype object, for which
    # np.asarray(x, dtype=float) makes a new view each call: caches keyed by the array missed
    import pickle

    y = pickle.loads(pickle.dumps(np.arange(5.0)))
    assert np.asarray(y, dtype=float) is not y  # what numpy does
    assert as_signal(y, "y") is y
    assert as_signal(y[1:], "y").base is y  # a view is kept as a view, not copied
    assert as_signal(np.arange(5), "y").dtype == np.float64
    with pytest.raises(InputError, match="y is complex"):
        as_signal(np.arange(5) + 1j, "y")
