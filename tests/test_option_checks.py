"""Each configuration object checks every option when it is made, before any data is read.

An integer option refuses ``3.0`` and ``True``, a number refuses NaN, a flag refuses
anything but True or False: a wrong option fails with a message that names it, not later
in a fit with a message about something else.
"""

import math

import pytest

from fosmodel.core import CandidateSpec, InputError, StopRule
from fosmodel.io import SplitSpec
from fosmodel.noise import UnitsSpec
from fosmodel.study import StudyConfig
from fosmodel.workflows import ImuConfig

GYRO = {"rate": 100.0, "sensor": "gyro", "units": "rad/s"}


@pytest.mark.parametrize("options, message", [
    ({"n_starts": 3.0}, "n_starts must be an integer >= 1, got 3.0"),
    ({"n_starts": True}, "n_starts must be an integer >= 1, got True"),
    ({"orders": (1, 2.0)}, r"every order must be an integer >= 1, got \[1, 2.0\]"),
    ({"orders": "12"}, "orders must be a sequence, got '12'"),
    ({"rate": math.nan}, "rate must be a finite number > 0, got nan"),
    ({"train_s": 0}, "train_s must be a finite number > 0, got 0"),
    ({"taus": ()}, "taus must hold at least one bias time"),
    ({"taus": (10.0, -1.0)}, "every tau must be a finite number > 0, got -1.0"),
    ({"levels": 1}, "levels must be True or False, got 1"),
    ({"fos_stop": "never"}, "stopping rule"),
])
def test_the_study_s_options_are_checked(options, message):
    with pytest.raises(InputError, match=message):
        StudyConfig(**{**GYRO, **options})


@pytest.mark.parametrize("options, message", [
    ({"n_jobs": 2.0}, "n_jobs must be an integer >= 1, got 2.0"),
    ({"loop_max_lag": 0}, "loop_max_lag must be an integer >= 1, got 0"),
    ({"min_tau": -1.0}, "min_tau must be a finite number > 0, got -1.0"),
    ({"loop_split": (0.6, -0.5)}, "each loop_split fraction must be a finite number > 0"),
    ({"loop_split": (0.5,)}, "loop_split must be the two fractions"),
    ({"n_starts": 0}, "n_starts must be an integer >= 1, got 0"),
])
def test_the_six_axis_workflow_s_options_are_checked(options, message):
    with pytest.raises(InputError, match=message):
        ImuConfig(**options)


def test_the_six_axis_defaults_pass():
    assert ImuConfig().n_jobs == 2


@pytest.mark.parametrize("train, evaluate, message", [
    ((0, "s"), (10, "s"), r"the train length must be \(value, unit\)"),
    ((10, "s"), (10, "days"), r"the evaluate length must be \(value, unit\)"),
    ((math.inf, "s"), (10, "s"), "the train length"),
    ((60, "%"), (40, "%"), "takes 100% of the record"),
])
def test_a_split_made_in_code_is_checked_as_a_parsed_one(train, evaluate, message):
    with pytest.raises(InputError, match=message):
        SplitSpec(train, evaluate)


def test_a_parsed_split_still_refuses_all_of_the_record():
    with pytest.raises(InputError, match="'50%,50%' takes 100% of the record"):
        SplitSpec.parse("50%,50%")


@pytest.mark.parametrize("options, message", [
    ({"every": "furlongs"}, "furlongs"),
    ({"every": 1.0}, "units must be a string such as 'deg/s', got 1.0"),
    ({"columns": {"": "deg/s"}}, "a column name must be a non-empty string"),
])
def test_units_made_in_code_are_checked_as_parsed_ones(options, message):
    with pytest.raises(InputError, match=message):
        UnitsSpec(**options)


def test_a_candidate_constant_must_be_a_bool():
    with pytest.raises(InputError, match="constant must be True or False, got 1"):
        CandidateSpec(constant=1)


@pytest.mark.parametrize("tol", ["0.1", True, None])
def test_a_tolerance_must_be_a_number(tol):
    with pytest.raises(InputError, match="needs a tolerance 0 < tol < 1"):
        StopRule("variance", tol=tol)
