"""Error models in a navigation filter: shaping filters, a Kalman filter, gyro arrays.

Fitted models and Allan fits as state-space shaping filters, a small linear Kalman filter,
and gyro arrays (averaging and the virtual gyro, with the correlation matrices of Koldbæk and
Totu, 2011).

Imports the layers below it (core, models, io, noise).  Its public names are imported on
first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .aided import (
        AidedRun,
        accelerometer_run,
        aided_position_run,
        compare_in_filter,
        integrate,
        position_fixes,
    )
    from .allan_statespace import (
        TermValue,
        allan_state_space,
        assemble_axes,
        initial_covariance,
        model_adev,
        model_terms,
    )
    from .arrays import (
        CORR_EQ_8_8,
        CORR_Q3,
        CORR_Q5,
        ArrayModel,
        angle_error_std,
        averaging_angle_std,
        averaging_rate_std,
        conditional_variance,
        constant_gain_filter,
        correlation,
        covariance,
        cross_gyro_comparison,
        kalman_angle_std,
        recursive_gain,
        steady_state_gain,
    )
    from .filter_file import FilterFile, read_filter_file, write_filter_file
    from .fos_filter import BiasComponent, DriverTerm, FOSFilterModel, FOSFilterResults
    from .joint_noise import JointNoise
    from .kalman import FilterRun, KalmanFilter, run_filter
    from .statespace import (
        NonlinearStateSpace,
        StateSpace,
        position_velocity_error_model,
        tilt_error_model,
        to_nonlinear_state_space,
        to_state_space,
    )
else:
    __getattr__, __dir__ = attach(__name__, {
        "allan_statespace": ("TermValue", "allan_state_space", "assemble_axes",
                             "initial_covariance", "model_adev", "model_terms"),
        "arrays": ("ArrayModel", "CORR_EQ_8_8", "CORR_Q3", "CORR_Q5", "angle_error_std",
                   "averaging_angle_std", "averaging_rate_std", "conditional_variance",
                   "constant_gain_filter", "correlation", "covariance", "cross_gyro_comparison",
                   "kalman_angle_std", "recursive_gain", "steady_state_gain"),
        "filter_file": ("FilterFile", "read_filter_file", "write_filter_file"),
        "joint_noise": ("JointNoise",),
        "kalman": ("FilterRun", "KalmanFilter", "run_filter"),
        "statespace": ("NonlinearStateSpace", "StateSpace", "position_velocity_error_model",
                       "tilt_error_model", "to_nonlinear_state_space", "to_state_space"),
        "aided": ("AidedRun", "accelerometer_run", "aided_position_run", "compare_in_filter",
                  "integrate", "position_fixes"),
        "fos_filter": ("BiasComponent", "DriverTerm", "FOSFilterModel", "FOSFilterResults"),
    })

__all__ = [
    "CORR_EQ_8_8", "CORR_Q3", "CORR_Q5", "ArrayModel", "FilterFile", "FilterRun", "JointNoise",
    "KalmanFilter", "NonlinearStateSpace", "StateSpace", "TermValue", "allan_state_space",
    "angle_error_std",
    "assemble_axes", "averaging_angle_std", "averaging_rate_std", "conditional_variance",
    "constant_gain_filter", "correlation", "covariance", "cross_gyro_comparison",
    "initial_covariance", "kalman_angle_std", "model_adev", "model_terms",
    "position_velocity_error_model", "read_filter_file", "recursive_gain", "run_filter",
    "steady_state_gain", "tilt_error_model", "to_nonlinear_state_space", "to_state_space",
    "write_filter_file",
    "AidedRun", "BiasComponent", "DriverTerm", "FOSFilterModel", "FOSFilterResults",
    "accelerometer_run", "aided_position_run", "compare_in_filter", "integrate",
    "position_fixes",
]
