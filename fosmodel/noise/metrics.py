"""Metrics every study table reports: unit scales, position errors, outage and one-step errors.

Two kinds of position error are computed here.

* :func:`equivalent_position_error` is Tamazin et al.'s (2013) metric (Tables 1-2): the
  position error after ``T`` seconds (3600 s in the paper) of an error whose RMS
  equals ``sqrt(MSE)`` held constant, ``0.5 sqrt(MSE) T^2`` for an accelerometer
  and ``g sqrt(MSE) T^3 / 6`` for a gyroscope (rate in rad/s, ``g = 9.81``).
* :func:`outage_metrics` looks at the update/prediction cycles of the AR-versus-
  Gauss-Markov study (10/10 s to 120/120 s): during an outage of ``H`` seconds the
  error model compensates the sensor by its *free-run* prediction, and whatever it
  misses integrates into position (:func:`integrated_position_error`).  One-step MSE at
  100-200 Hz is dominated by white noise and hides the slow errors these show.

Two gravities appear and are kept apart: :data:`STANDARD_GRAVITY` (9.80665 m/s^2)
converts readings in ``"g"`` and ``"mg"`` to m/s^2, while :data:`PAPER_GRAVITY`
(9.81 m/s^2, Tamazin et al.'s (2013) value) turns a tilt error into an acceleration error.

References
----------
.. [1] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InputError, UnstableModelWarning
from ..core.validation import as_signal, check_positive, did_you_mean

#: Standard gravity in m/s^2, used only to convert the units "g" and "mg".
STANDARD_GRAVITY = 9.80665
#: Gravity of Tamazin et al.'s (2013) gyroscope position error, g * tilt -> acceleration error.
PAPER_GRAVITY = 9.81

_SI_SCALES: dict[str, dict[str, float]] = {
    "accel": {"m/s^2": 1.0, "g": STANDARD_GRAVITY, "mg": 1e-3 * STANDARD_GRAVITY},
    "gyro": {"rad/s": 1.0, "deg/s": math.pi / 180.0, "deg/h": math.pi / 180.0 / 3600.0},
}


class FreeRunModel(Protocol):
    """What the outage metrics need of a model (FOSModel and the AR baselines).

    A model may also have ``free_runs(y, starts, n_steps)``, all the runs
    ``simulate(y[:s], n_steps)`` at once (FOSModel's vectorised path); the
    metrics use it when it is there.
    """

    def simulate(self, y_init: np.ndarray, n_steps: int) -> np.ndarray:
        """Free-run continuation of ``y_init``, ``n_steps`` samples."""


class OneStepModel(FreeRunModel, Protocol):
    """A model that also predicts one step ahead: FOSModel, a baseline, a bound model."""

    def predict(self, y: np.ndarray) -> np.ndarray:
        """Return the one-step prediction of ``y``, aligned with it."""


# -- units and the paper's equivalent position error ----------------------------------


def to_si_scale(sensor: str, units: str) -> float:
    """Factor turning a reading in ``units`` into rad/s (gyro) or m/s^2 (accel).

    Parameters
    ----------
    sensor : {"accel", "gyro"}
    units : str
        Gyroscope: "rad/s", "deg/s", "deg/h"; accelerometer: "m/s^2", "g", "mg"
        ("g" is standard gravity, 9.80665 m/s^2).

    Raises
    ------
    InputError
        Unknown sensor or units; the message lists the valid ones.
    """
    if sensor not in _SI_SCALES:
        raise InputError(f"unknown sensor {sensor!r}{did_you_mean(str(sensor), _SI_SCALES)}; "
                         f"valid sensors: {', '.join(_SI_SCALES)}")
    scales = _SI_SCALES[sensor]
    if units not in scales:
        raise InputError(f"unknown {sensor} units {units!r}{did_you_mean(str(units), scales)}; "
                         f"valid {sensor} units: {', '.join(scales)}")
    return scales[units]


def is_sensor_units(units: str) -> bool:
    """Tell whether a gyro or an accelerometer reads in ``units`` (a temperature's degC: no)."""
    return any(units in scales for scales in _SI_SCALES.values())


def sensor_of(units: str) -> str:
    """Return the sensor that reads in ``units``: no unit belongs to both.

    Examples
    --------
    >>> sensor_of("deg/h"), sensor_of("mg")
    ('gyro', 'accel')

    Raises
    ------
    InputError
        Unknown units; the message lists the valid ones of each sensor.
    """
    for sensor, scales in _SI_SCALES.items():
        if units in scales:
            return sensor
    known = [u for scales in _SI_SCALES.values() for u in scales]
    raise InputError(f"unknown units {units!r}{did_you_mean(str(units), known)}; valid units: "
                     + "; ".join(f"{', '.join(scales)} ({sensor})"
                                 for sensor, scales in _SI_SCALES.items()))


def equivalent_position_error(
    mse: float, sensor: str, units: str, horizon_s: float = 3600.0, g: float = PAPER_GRAVITY
) -> float:
    """Return Tamazin et al.'s (2013) position error (m) of a model MSE after ``horizon_s`` seconds.

    With ``s = sqrt(mse)`` in SI units and ``T = horizon_s``: accelerometer
    ``0.5 s T^2``; gyroscope ``g s T^3 / 6`` (s in rad/s), i.e. a constant error of
    size ``s`` integrated over ``T`` (compare :func:`integrated_position_error`).

    Parameters
    ----------
    mse : float
        Model MSE in the squared ``units`` (e.g. (deg/h)^2).
    sensor : {"accel", "gyro"}
    units : str
        See :func:`to_si_scale`.
    horizon_s : float
        T in seconds; the paper uses one hour.
    g : float
        Gravity turning a tilt into an acceleration error (the paper's 9.81 m/s^2,
        distinct from the standard gravity that converts "g" units).

    Returns
    -------
    float
        Position error in metres.
    """
    if not (isinstance(mse, (int, float, np.integer, np.floating)) and math.isfinite(mse)
            and mse >= 0):
        raise InputError(f"mse must be a finite number >= 0, got {mse!r}")
    rms = math.sqrt(mse) * to_si_scale(sensor, units)
    t = check_positive(horizon_s, "horizon_s")
    if sensor == "accel":
        return 0.5 * rms * t**2
    return check_positive(g, "g") * rms * t**3 / 6.0


def segment_text(name: str, segment: slice, rate: float) -> str:
    """Name a segment with its bounds: ``the prediction segment (360-600 s of the record)``."""
    return (f"the {name} segment ({segment.start / rate:.6g}-{segment.stop / rate:.6g} s of "
            "the record)")


def metric_definitions(units: str | None, horizon_s: float, n_starts: int, predict: str,
                       evaluate: str = "the evaluation segment") -> dict[str, str]:
    """Define each metric the reports show, where it is shown: its units, horizon, segment.

    Parameters
    ----------
    units : str or None
        The record's units (None: ``units``).
    horizon_s, n_starts : float, int
        The outages of :func:`outage_metrics`.
    predict, evaluate : str
        The segments the errors and the choices are on, as :func:`segment_text` names them.

    Returns
    -------
    dict
        A sentence per metric: ``mse``, ``evaluate_mse``, ``position_error_m`` (the FOS
        paper's equivalent position error), ``outage_mse``, ``outage_position_error_m``,
        ``bias_rms`` (of the one-step residual) and ``free_run_bias_rms`` (of the free runs).
    """
    u = units or "units"
    return {
        "mse": f"MSE ({u})^2: the mean square of the one-step prediction error on {predict}.",
        "evaluate_mse": f"Evaluate MSE ({u})^2: the same on {evaluate}, where each method's "
                        "order (and level) is chosen.",
        "position_error_m": "Position error (m): the equivalent position error of "
                            "Tamazin et al. (2013), "
                            "T = 3600 s: an error of constant size sqrt(MSE) integrated freely "
                            "for an hour, 0.5 sqrt(MSE) T^2 for an accelerometer and "
                            "g sqrt(MSE) T^3 / 6 for a gyroscope (rad/s, g = 9.81 m/s^2). It "
                            "ranks models by their one-step error on the paper's scale; no "
                            "navigation run drifts an hour unaided, so it is not a position "
                            "error to expect.",
        "outage_mse": f"Outage MSE ({u})^2: the mean square of the error of the model's "
                      f"{horizon_s:g} s free runs from the true past ({n_starts} outages spread "
                      f"evenly over {predict}), over every step.",
        "outage_position_error_m": f"Outage position error (m, {horizon_s:g} s): in each of "
                                   f"{n_starts} outages of {horizon_s:g} s spread evenly over "
                                   f"{predict}, the model's free run from the true past "
                                   "compensates the sensor and what it misses is integrated "
                                   "into position "
                                   "(an accelerometer's twice; a gyroscope's once into a tilt, "
                                   "times g = 9.81 m/s^2, then twice); the RMS over the outages "
                                   "of the position error at their ends.",
        "bias_rms": f"One-step bias RMS tau s ({u}): the RMS of the means of the one-step "
                    f"residual over consecutive tau-second windows of {predict}: the slow "
                    "error a filter sees as a bias.",
        "free_run_bias_rms": f"Free-run bias RMS tau s ({u}): the RMS over the outages of "
                             f"tau s spread evenly over {predict} of the mean error of the "
                             "model's free run from the true past: the bias left to a filter "
                             "that integrates the model unaided.",
    }


def caption_note(horizon_s: float, n_starts: int, predict: str) -> str:
    """Define a table's metrics in one sentence, for its caption (:func:`metric_definitions`)."""
    return (f"Errors on {predict}: MSE of the one-step prediction; position error, the FOS "
            "paper's equivalent position error (an error of size sqrt(MSE) integrated for "
            f"T = 3600 s); outage position error, the RMS at the end of {n_starts} free runs of "
            f"{horizon_s:g} s from the true past; bias RMS, the RMS of the one-step residual's "
            "means over windows of the length given")


# -- outages ---------------------------------------------------------------------------


def _index(value: int, name: str, minimum: int) -> int:
    """``value`` as an int, refusing bools, non-integers and values below ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def outage_starts(start: int, stop: int, n_steps: int, count: int = 20) -> np.ndarray:
    """Evenly spaced outage start indices ``s`` in ``[start, stop - n_steps]``.

    Each outage ``y[s:s+n_steps]`` then lies inside ``y[start:stop]``.  The first
    start is ``start`` and the last ``stop - n_steps``; a segment with fewer than
    ``count`` possible starts gives all of them.

    Returns
    -------
    ndarray of int, increasing, at most ``count`` long

    Raises
    ------
    InputError
        Not even one horizon fits in the segment (the lengths are named).
    """
    start = _index(start, "start", 0)
    stop = _index(stop, "stop", 0)
    n_steps = _index(n_steps, "n_steps", 1)
    count = _index(count, "count", 1)
    last = stop - n_steps
    if last < start:
        raise InputError(f"the segment [{start}, {stop}) has {max(stop - start, 0)} samples, "
                         f"shorter than one outage horizon of {n_steps} samples")
    return np.unique(np.round(np.linspace(start, last, count)).astype(np.int64))


def free_run_errors(
    model: FreeRunModel, y: ArrayLike, starts: Iterable[int], n_steps: int
) -> np.ndarray:
    """Free-run errors ``y[s:s+n_steps] - model.simulate(y[:s], n_steps)`` for each start.

    The model starts each outage from the true past ``y[:s]``.  A free run that
    diverges (NaN from the model) leaves NaN in its row.

    Parameters
    ----------
    model : object with ``simulate(y_init, n_steps)``
    y : array-like of shape (N,)
        The record, in the model's units.
    starts : iterable of int
        Outage starts, e.g. from :func:`outage_starts`.
    n_steps : int
        Outage length in samples.

    Returns
    -------
    ndarray of shape (len(starts), n_steps)
    """
    y = as_signal(y, "y")
    n_steps = _index(n_steps, "n_steps", 1)
    s = np.asarray([_index(v, "outage start", 0) for v in starts], dtype=np.int64)
    if s.size and s.max() + n_steps > len(y):
        raise InputError(f"an outage starting at sample {s.max()} needs {n_steps} samples, "
                         f"but y has {len(y)}")
    return _free_run_errors(model, y, s, n_steps)


def _free_run_errors(model: FreeRunModel, y: np.ndarray, s: np.ndarray,
                     n_steps: int) -> np.ndarray:
    """:func:`free_run_errors` of a checked record ``y`` and outage starts ``s`` inside it."""
    truth = y[s[:, None] + np.arange(n_steps)]
    if hasattr(model, "free_runs"):
        runs = model.free_runs(y, s, n_steps)
        if np.isnan(runs).any():
            warnings.warn(UnstableModelWarning(
                "a free run diverged; its samples from the divergence on are NaN"), stacklevel=2)
    else:
        runs = [np.asarray(model.simulate(y[:k], n_steps), dtype=float) for k in s]
    return truth - np.reshape(runs, truth.shape)


def _hold_weights(n_steps: int, rate: float, order: int) -> np.ndarray:
    """Weights of the exact ``order``-fold integral, at the end, of a sample-and-hold signal.

    A unit value held over ``[a, b]`` integrates ``order`` times to
    ``((H - a)^order - (H - b)^order) / order!`` at ``H``.
    """
    r = np.arange(n_steps, 0, -1, dtype=float)  # (H - a) * rate for each sample
    # r^m - (r-1)^m as a sum of positive terms: no cancellation for long rows
    diff = sum((r**i * (r - 1.0) ** (order - 1 - i) for i in range(order)), np.zeros_like(r))
    return diff / (math.factorial(order) * rate**order)


def integrated_position_error(
    errors: ArrayLike, rate: float, sensor: str, units: str, g: float = PAPER_GRAVITY
) -> np.ndarray:
    """Position error (m) at the end of each outage row of sensor-error samples.

    Accelerometer: the acceleration error integrated twice.  Gyroscope: the rate
    error integrated once to a tilt ``theta``, and the acceleration error ``g theta``
    integrated twice.  Both start from zero error at the start of the row.

    Integration rule: each sample's error is *held* over its sample interval
    ``[k/rate, (k+1)/rate)`` (as a strapdown mechanisation applies it) and this
    piecewise-constant signal is integrated exactly, so the row covers
    ``H = n/rate`` seconds.  Constants are therefore exact: a bias ``b`` gives
    ``b H^2 / 2`` and a gyro bias ``w`` gives ``g w H^3 / 6``, the formulas of
    :func:`equivalent_position_error`.  A ramp sampled at the sample times,
    ``e[k] = r k / rate``, gives ``r dt^(m+1)/m! * sum_{j<n} j^m`` (``m`` = 2 or 3
    integrations, ``dt = 1/rate``), which tends to ``r H^(m+1)/(m+1)!``.

    Parameters
    ----------
    errors : array-like of shape (..., n)
        Sensor-error samples over one outage per row, in ``units``; NaN propagates.
    rate : float
        Sampling rate in Hz.
    sensor : {"accel", "gyro"}
    units : str
        See :func:`to_si_scale`.
    g : float
        Gravity turning a tilt into an acceleration error (paper: 9.81 m/s^2).

    Returns
    -------
    ndarray of shape ``errors.shape[:-1]``
    """
    e = np.asarray(errors, dtype=float)
    if e.ndim not in (1, 2) or e.shape[-1] == 0:
        raise InputError(f"errors must be 1-D or 2-D with at least one sample per row, "
                         f"got shape {e.shape}")
    scale = to_si_scale(sensor, units)
    rate = check_positive(rate, "rate")
    if sensor == "accel":
        return np.asarray(e @ _hold_weights(e.shape[-1], rate, 2) * scale)
    return np.asarray(e @ _hold_weights(e.shape[-1], rate, 3) * (scale * check_positive(g, "g")))


def bias_rms(residual: ArrayLike, rate: float, tau_s: float) -> float:
    """RMS of the means of ``residual`` over non-overlapping windows of ``tau_s`` seconds.

    A window holds ``round(tau_s * rate)`` samples; the incomplete window at the end
    is dropped.  No mean is removed: a constant ``c`` gives ``|c|``, white noise of
    standard deviation ``s`` about ``s / sqrt(tau_s * rate)``.

    Parameters
    ----------
    residual : array-like of shape (N,)
        One-step residual; must be finite (slice off the model's lag window first).
    rate : float
        Sampling rate in Hz.
    tau_s : float
        Window length in seconds.

    Raises
    ------
    InputError
        Non-finite residual (the first such sample is named), a window shorter than
        one sample, or fewer than 2 windows fitting in the residual.
    """
    return _bias_rms(_finite_residual(residual), rate, tau_s)


def _finite_residual(residual: ArrayLike) -> np.ndarray:
    """Return ``residual`` as checked by :func:`as_signal`, or say that bias_rms needs it finite.

    Raises
    ------
    InputError
        Not a finite 1-D signal.
    """
    try:
        return as_signal(residual, "residual")
    except InputError as exc:
        raise InputError(f"{exc}; bias_rms needs a finite residual "
                         "(slice off the model's lag window first)") from None


def _bias_rms(r: np.ndarray, rate: float, tau_s: float) -> float:
    """:func:`bias_rms` of a checked residual ``r``."""
    width = round(check_positive(tau_s, "tau_s") * check_positive(rate, "rate"))
    if width < 1:
        raise InputError(f"tau_s={tau_s} s is shorter than one sample at {rate} Hz")
    n_windows = len(r) // width
    if n_windows < 2:
        raise InputError(f"residual has {len(r)} samples, fewer than the 2 windows of "
                         f"{width} samples (tau_s={tau_s} s at {rate} Hz) bias_rms needs")
    means = r[: n_windows * width].reshape(n_windows, width).mean(axis=1)
    return float(np.sqrt(np.mean(means**2)))


def _segment_bounds(segment: slice, length: int) -> tuple[int, int]:
    """``(start, stop)`` of a step-1 slice over ``length`` samples."""
    if not isinstance(segment, slice):
        raise InputError(f"segment must be a slice, got {type(segment).__name__}")
    start, stop, step = segment.indices(length)
    if step != 1:
        raise InputError(f"segment must have step 1, got {step}")
    if stop <= start:
        raise InputError(f"segment {segment} is empty in a record of {length} samples")
    return start, stop


def outage_metrics(
    model: OneStepModel,
    y: ArrayLike,
    rate: float,
    sensor: str | None,
    units: str | None,
    segment: slice,
    horizon_s: float = 30.0,
    n_starts: int = 20,
    taus: Iterable[float] = (1.0, 10.0, 30.0),
    residual: ArrayLike | None = None,
    g: float = PAPER_GRAVITY,
) -> dict:
    """Outage (free-run) errors, their position error, and the residual's bias RMS.

    These are the update/prediction cycles of the AR-versus-Gauss-Markov study seen
    from the model side: during an outage of ``horizon_s`` seconds the error model
    compensates the sensor by its free-run prediction from the true past, and what
    it misses integrates into position.  ``n_starts`` outages are spread evenly over
    ``segment`` (:func:`outage_starts`).

    Parameters
    ----------
    model : object with ``simulate(y_init, n_steps)``
        And ``predict(y)`` (aligned with ``y``) when ``residual`` is None.
    y : array-like of shape (N,)
        The record, in ``units``.
    rate : float
        Sampling rate in Hz.
    sensor, units : str or None
        See :func:`to_si_scale`; with ``sensor`` None the position error is None.
    segment : slice
        The evaluation part of ``y`` (step 1); outages lie entirely inside it.
    horizon_s : float
        Outage length H in seconds (``round(H * rate)`` samples).
    n_starts : int
        Number of outages.
    taus : iterable of float
        Window lengths in seconds for :func:`bias_rms`.
    residual : array-like, optional
        The one-step residual over ``segment`` (``y - model.predict(y)`` sliced
        there); computed when not given.  Must be finite.
    g : float
        Gravity of the gyroscope position error (paper: 9.81 m/s^2).

    Returns
    -------
    dict
        ``"outage_mse"``: mean squared free-run error over all starts and steps;
        ``"outage_position_error_m"``: RMS over starts of the end-of-outage position
        error; ``"bias_rms"``: ``{tau: value}`` of the one-step residual.
    """
    y = as_signal(y, "y")
    start, stop = _segment_bounds(segment, len(y))
    n_steps = round(check_positive(horizon_s, "horizon_s") * check_positive(rate, "rate"))
    if n_steps < 1:
        raise InputError(f"horizon_s={horizon_s} s is shorter than one sample at {rate} Hz")
    # y is checked here and the residual below, once each: not again per free run or tau
    errors = _free_run_errors(model, y, outage_starts(start, stop, n_steps, n_starts), n_steps)
    position = None
    if sensor is not None:
        if units is None:
            raise InputError(f"the {sensor} position error needs the record's units")
        position = integrated_position_error(errors, rate, sensor, units, g)
    if residual is None:
        residual = (y - np.asarray(model.predict(y), dtype=float))[start:stop]
    residual = np.asarray(residual, dtype=float)
    if residual.shape != (stop - start,):
        raise InputError(f"residual has shape {residual.shape}, but the segment "
                         f"[{start}, {stop}) has {stop - start} samples")
    checked = _finite_residual(residual)
    with np.errstate(over="ignore"):  # a diverging run (an unstable model) squares to inf
        rms_position = None if position is None else float(np.sqrt(np.mean(position**2)))
        outage_mse = float(np.mean(errors**2))
    return {
        "outage_mse": outage_mse,
        "outage_position_error_m": rms_position,
        "bias_rms": {tau: _bias_rms(checked, rate, tau) for tau in taus},
    }


def one_step_mse(y: ArrayLike, prediction: ArrayLike, segment: slice) -> float:
    """Mean squared one-step error ``y - prediction`` over ``segment``.

    Raises
    ------
    InputError
        Lengths differ, the segment is empty, or a prediction in it is NaN (the
        segment starts inside the model's lag window); the first such sample is named.
    """
    y = as_signal(y, "y")
    pred = np.asarray(prediction, dtype=float)
    if pred.shape != y.shape:
        raise InputError(f"prediction has shape {pred.shape}, y has {y.shape}")
    start, stop = _segment_bounds(segment, len(y))
    error = np.subtract(y[start:stop], pred[start:stop])
    mse = float(np.mean(np.square(error, out=error)))
    if not math.isfinite(mse):  # y is finite: a NaN prediction, or one so large it overflows
        bad = np.flatnonzero(~np.isfinite(pred[start:stop]))
        if bad.size:
            raise InputError(f"prediction is NaN at sample {start + bad[0]} inside the segment "
                             f"[{start}, {stop}); start the segment after the model's lag "
                             "window")
    return mse
