"""A split as a user gives it (SplitSpec): each length a duration or a percent of the record,
resolved against the record into the one Split of the harness and the loop."""

import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io.split import Split, SplitSpec

N, RATE = 60_000, 100.0  # 600 s


@pytest.mark.parametrize(("text", "seconds", "fractions"), [
    ("180s,180s", (180.0, 180.0), (0.3, 0.3)),
    ("3min,3min", (180.0, 180.0), (0.3, 0.3)),
    ("0.05h, 90 s", (180.0, 90.0), (0.3, 0.15)),
    ("50%,20%", (300.0, 120.0), (0.5, 0.2)),
    ("1e2s,25%", (100.0, 150.0), (1 / 6, 0.25)),
])
def test_each_length_in_seconds_and_as_a_fraction(text, seconds, fractions):
    spec = SplitSpec.parse(text)
    assert spec.seconds(N, RATE) == pytest.approx(seconds, rel=1e-12)
    assert spec.fractions(N, RATE) == pytest.approx(fractions, rel=1e-12)


def test_the_old_defaults_resolve_to_the_same_numbers_exactly():
    """The harness's 180 s + 180 s and the loop's 0.5 + 0.2, bit for bit."""
    assert SplitSpec.parse("180s,180s").seconds(N, RATE) == (180.0, 180.0)
    assert SplitSpec.parse("50%,20%").fractions(N, RATE) == (0.5, 0.2)


@pytest.mark.parametrize("text", ["180s,180s", "50%,20%", "1min,25%", "33.3%,12.5s"])
@pytest.mark.parametrize(("n", "rate"), [(60_000, 100.0), (12_345, 7.0), (90_001, 200.0)])
def test_seconds_and_fractions_give_the_same_segments(text, n, rate):
    spec = SplitSpec.parse(text)
    by_time = Split.by_duration(n, rate, *spec.seconds(n, rate))
    assert Split.by_fraction(n, *spec.fractions(n, rate)) == by_time


def test_it_prints_as_it_reads():
    for text in ("180s,180s", "3min,25%", "0.5h,10%"):
        assert str(SplitSpec.parse(text)) == text
        assert SplitSpec.parse(str(SplitSpec.parse(text))) == SplitSpec.parse(text)


USAGE = ("expected TRAIN,EVALUATE with units: durations like 180s,180s (s, min or h) or "
         "percents of the record like 50%,20%, got ")


@pytest.mark.parametrize("text", ["180,180", "0.5,0.2", "180s,180", "180s", "1s,2s,3s", "0s,10s",
                                  "-5s,10s", "5ms,1s", "infs,1s", "nan%,10%", "", "s,s"])
def test_a_length_without_a_unit_or_not_positive_is_refused(text):
    with pytest.raises(InputError) as err:
        SplitSpec.parse(text)
    assert str(err.value) == USAGE + repr(text)


def test_percents_that_leave_nothing_to_predict_are_refused():
    with pytest.raises(InputError) as err:
        SplitSpec.parse("60%,40%")
    assert str(err.value) == ("the split '60%,40%' takes 100% of the record for training and "
                              "evaluation and leaves nothing to predict")


def test_durations_longer_than_the_record_leave_no_fraction_to_predict():
    spec = SplitSpec.parse("5min,6min")
    assert spec.seconds(N, RATE) == (300.0, 360.0)  # the harness says what is too short
    with pytest.raises(InputError) as err:
        spec.fractions(N, RATE)
    assert str(err.value) == ("the split 5min,6min leaves nothing of the record (60000 samples, "
                              "600 s at 100 Hz) to predict")
