"""Noise analysis of a record: Allan deviation and its fit, denoisers, error metrics.

The Allan deviation (``allan``), its IEEE Std 952 fit (``allan_fit``) and their figure and
files (``allan_report``), for one axis or a whole IMU (``imu_noise``, with the Kalibr, MATLAB
and JSON exports), the denoisers of the paper protocol, and the error metrics every
study reports (equivalent position error, outages, bias).

Imports the layers below it (core, typeset, models, io).  Its public names are imported on
first use (:mod:`fosmodel._lazy`); the function ``imu_noise()`` is :func:`fosmodel.imu_noise`
(here ``fosmodel.noise.imu_noise`` is its module).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .allan import AllanResult, allan_deviation, averaging_factors, readoff, spectral_line
    from .allan_fit import TERMS, NoiseFit, fit_noise
    from .allan_report import allan_figure, write_allan
    from .axes import Axis, UnitsSpec, infer_axis, resolve_axes
    from .denoise import kaiser_lowpass, wavelet_lowpass
    from .imu_noise import AxisNoise, ImuNoise, write_imu_noise
    from .metrics import (
        STANDARD_GRAVITY,
        bias_rms,
        equivalent_position_error,
        free_run_errors,
        one_step_mse,
        outage_metrics,
        to_si_scale,
    )
else:
    __getattr__, __dir__ = attach(__name__, {
        "allan": ("AllanResult", "allan_deviation", "averaging_factors", "readoff",
                  "spectral_line"),
        "allan_fit": ("NoiseFit", "TERMS", "fit_noise"),
        "allan_report": ("allan_figure", "write_allan"),
        "axes": ("Axis", "UnitsSpec", "infer_axis", "resolve_axes"),
        "denoise": ("kaiser_lowpass", "wavelet_lowpass"),
        "imu_noise": ("AxisNoise", "ImuNoise", "write_imu_noise"),
        "metrics": ("STANDARD_GRAVITY", "bias_rms", "equivalent_position_error",
                    "free_run_errors", "one_step_mse", "outage_metrics", "to_si_scale"),
    })

__all__ = [
    "STANDARD_GRAVITY", "TERMS", "AllanResult", "Axis", "AxisNoise", "ImuNoise", "NoiseFit",
    "UnitsSpec", "allan_deviation", "allan_figure", "averaging_factors", "bias_rms",
    "equivalent_position_error", "fit_noise", "free_run_errors", "infer_axis", "kaiser_lowpass",
    "one_step_mse", "outage_metrics", "readoff", "resolve_axes", "spectral_line", "to_si_scale",
    "wavelet_lowpass", "write_allan", "write_imu_noise",
]
