"""Temperature-dependent error models of a thermal-chamber record (El-Diasty et al. 2007).

El-Diasty et al. (2007) hold a MEMS IMU at chamber temperatures from -30 to +60 C and report,
per temperature, the white-noise coefficient (ARW/VRW, Table 1) and a first-order AR coefficient
with its standard error (Table 2).  This module does the same on a record with a temperature
column, and sets the per-temperature approach against one FOS model with temperature as an
exogenous input:

* :func:`temperature_segments` finds the plateaus of the temperature column (steady stretches,
  transitions dropped);
* :func:`segment_table` fits the error model per plateau: the bias, the noise level and an
  AR(p) model by FOS, with standard errors (:func:`term_standard_errors`, statsmodels OLS on
  the selected terms; the bias's from the AR model's long-run variance);
  :func:`segment_noise` adds the Allan white-noise coefficient per plateau;
* :class:`TableModel` turns the table into a model for any temperature (each coefficient a
  weighted polynomial in temperature), the classic calibration-table approach;
* :func:`held_out_comparison` scores that table model, a FOS model with ``temp_c`` lags and
  its square fitted across the training plateaus (:func:`global_models`), and the same FOS
  model without temperature, leaving one plateau out at a time (one-step MSE and free-run
  outage metrics).

References
----------
.. [1] M. El-Diasty, A. El-Rabbany and S. Pagiatakis, "Stochastic Characteristics of
   Temperature-Dependent MEMS-Based Inertial Sensor Error", Proceedings of the ION
   National Technical Meeting, San Diego, CA, 2007.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
import statsmodels.api as sm
from numpy.polynomial import Polynomial
from numpy.typing import ArrayLike

from ..core.candidates import OUTPUT, Term, evaluate_terms
from ..core.exceptions import InputError
from ..core.validation import as_signal
from ..models.bound import BoundModel
from ..models.model import FOSModel
from ..noise.allan import allan_deviation
from ..noise.allan_fit import fit_noise
from ..noise.metrics import one_step_mse, outage_metrics

TEMP, TEMP_SQ = "temp_c", "temp_c_sq"


# -- plateaus ------------------------------------------------------------------------------


def _window_means(x: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``x`` over ``[n - w, n)`` and ``[n, n + w)`` (shortened at the ends)."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    n = np.arange(len(x))
    lo, hi = np.maximum(n - w, 0), np.minimum(n + w, len(x))
    back = (c[n] - c[lo]) / np.maximum(n - lo, 1)
    ahead = (c[hi] - c[n]) / (hi - n)
    back[0] = ahead[0]
    return back, ahead


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of every run of True in ``mask``."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return list(zip(edges[::2], edges[1::2]))


def _fill_gaps(mask: np.ndarray, width: int) -> np.ndarray:
    """``mask`` with runs of False shorter than ``width`` between two True runs set to True."""
    out = mask.copy()
    for start, stop in _runs(~mask):
        if 0 < start and stop < len(mask) and stop - start < width:
            out[start:stop] = True
    return out


def temperature_segments(
    temp: ArrayLike,
    rate: float,
    *,
    smooth_s: float = 10.0,
    max_slope: float = 0.005,
    settle_c: float = 0.25,
    min_duration_s: float = 60.0,
) -> list[slice]:
    """Plateaus of a temperature column: steady stretches with the transitions left out.

    A sample is steady when the mean temperature over the next ``smooth_s`` seconds differs
    from the mean over the previous ``smooth_s`` seconds by at most ``max_slope * smooth_s``
    (two adjacent means, so read-out noise of standard deviation ``s`` enters the slope only as
    ``s sqrt(2 / (smooth_s rate)) / smooth_s``).  Unsteady gaps shorter than ``smooth_s`` are
    filled.  Each steady stretch is then trimmed at both ends to the samples whose smoothed
    temperature is within ``settle_c`` of the stretch's level (the median of its second half),
    which drops the tail of a first-order approach, and kept if it lasts ``min_duration_s``.

    Parameters
    ----------
    temp : array-like
        Temperature samples (deg C).
    rate : float
        Sampling rate in Hz.
    smooth_s : float
        Averaging window in seconds.
    max_slope : float
        Largest steady slope in deg C per second.
    settle_c : float
        Largest distance of a plateau sample's smoothed temperature from the plateau level.
    min_duration_s : float
        Shortest plateau kept, in seconds.

    Returns
    -------
    list of slice
        Sample ranges of the plateaus, in time order.
    """
    t = as_signal(temp, "temperature")
    if not rate > 0:
        raise InputError(f"rate must be > 0, got {rate!r}")
    w = max(1, round(smooth_s * rate))
    back, ahead = _window_means(t, w)
    steady = _fill_gaps(np.abs(ahead - back) <= max_slope * w / rate, w)
    smooth = 0.5 * (back + ahead)
    out = []
    for start, stop in _runs(steady):
        level = np.median(t[(start + stop) // 2 : stop])
        close = np.flatnonzero(np.abs(smooth[start:stop] - level) <= settle_c)
        if close.size and (close[-1] + 1 - close[0]) / rate >= min_duration_s:
            out.append(slice(int(start + close[0]), int(start + close[-1]) + 1))
    return out


# -- per-plateau models ----------------------------------------------------------------------


def _design(
    model: FOSModel, y: np.ndarray, exog: Mapping[str, ArrayLike] | None, runs: Sequence[slice]
) -> tuple[np.ndarray, np.ndarray]:
    """Return the selected terms of a fitted model (centred as in the fit) and the centred output.

    Raises
    ------
    InputError
        The model reads a channel that ``exog`` lacks.
    """
    signals = {OUTPUT: y - model.offsets_[OUTPUT]}
    given: Mapping[str, ArrayLike] = exog if exog is not None else {}
    channels = [*model.spec_.exog_lags, *model.spec_.columns]
    missing = [ch for ch in channels if ch not in given]
    if missing:
        raise InputError(f"the model reads {', '.join(missing)}; pass them in exog")
    for ch in channels:
        signals[ch] = as_signal(given[ch], ch) - model.offsets_[ch]
    terms = [Term.parse(name) for name in model.terms_]
    n0 = model.lag_window_
    pieces = [{k: v[s] for k, v in signals.items()} for s in runs if s.stop - s.start > n0]
    x = np.vstack([evaluate_terms(terms, p, n0) for p in pieces])
    target = np.concatenate([p[OUTPUT][n0:] for p in pieces])
    return x, target


def term_standard_errors(
    model: FOSModel,
    y: ArrayLike,
    exog: Mapping[str, ArrayLike] | None = None,
    segments: Sequence[slice] | None = None,
) -> pd.DataFrame:
    """Coefficients of a fitted FOS model's terms with least-squares standard errors.

    Refits the selected terms (and the constant) by statsmodels OLS on the samples the model
    was fitted on, which reproduces FOS's weights, and takes the standard errors from
    ``sigma^2 (X'X)^-1``.  They are conditional on the selection (FOS chose the terms on the
    same data, so they understate the uncertainty of a data-driven choice).

    Parameters
    ----------
    model : FOSModel
        Fitted on ``y`` (and ``exog``, ``segments``).
    y, exog, segments
        As given to :meth:`FOSModel.fit`.

    Returns
    -------
    DataFrame
        ``term`` (``"1"`` first), ``coef``, ``se``.
    """
    y = as_signal(y, "y")
    runs = list(segments) if segments is not None else [slice(0, len(y))]
    x, target = _design(model, y, exog, runs)
    fit = sm.OLS(target, sm.add_constant(x, has_constant="add")).fit()
    return pd.DataFrame({"term": ["1", *model.terms_], "coef": fit.params, "se": fit.bse})


def segment_table(
    y: ArrayLike, temp: ArrayLike, segments: Sequence[slice], order: int = 1
) -> pd.DataFrame:
    """Error model per plateau: bias, noise level and AR(``order``) coefficients with SEs.

    Each plateau gets ``FOSModel(max_lag=order, stop="max_terms", max_terms=order)``, the
    least-squares AR(``order``) model whose terms FOS orders by their MSE reduction
    (El-Diasty et al. 2007, Table 2 is the case ``order=1``), and
    :func:`term_standard_errors`.  The bias is the plateau mean; its standard error comes from
    the fitted model's long-run variance,
    ``sqrt(s_e^2 / n) / |1 - sum_l a_l|`` (the AR spectrum at zero frequency), which is
    ``sigma / sqrt(n)`` for white noise and larger for positively correlated noise.

    Returns
    -------
    DataFrame
        One row per plateau: ``start``, ``stop``, ``n``, ``temp_c`` (mean), ``temp_sd``,
        ``bias``, ``bias_se``, ``sigma`` (standard deviation), ``sigma_se`` (``sigma/sqrt(2n)``),
        and ``coef <term>`` / ``se <term>`` for ``y[n-1] .. y[n-order]``.
    """
    y, temp = as_signal(y, "y"), as_signal(temp, "temperature")
    rows = []
    for s in segments:
        piece = y[s]
        model = FOSModel(max_lag=order, stop="max_terms", max_terms=order).fit(piece)
        terms = term_standard_errors(model, piece).set_index("term")
        gain = abs(1.0 - model.coef_.sum())
        sigma = float(np.std(piece, ddof=1))
        row = {"start": s.start, "stop": s.stop, "n": s.stop - s.start,
               "temp_c": float(np.mean(temp[s])), "temp_sd": float(np.std(temp[s])),
               "bias": float(np.mean(piece)),
               "bias_se": float(np.sqrt(model.mse_path_[-1] / len(piece)) / gain),
               "sigma": sigma, "sigma_se": sigma / np.sqrt(2 * len(piece))}
        for lag in range(1, order + 1):
            name = f"{OUTPUT}[n-{lag}]"
            row[f"coef {name}"], row[f"se {name}"] = terms.loc[name, ["coef", "se"]]
        rows.append(row)
    return pd.DataFrame(rows)


def segment_noise(
    y: ArrayLike, rate: float, segments: Sequence[slice], sensor: str, units: str
) -> pd.DataFrame:
    """Allan white-noise coefficient per plateau in navigation units (El-Diasty et al. 2007).

    Returns
    -------
    DataFrame
        ``noise`` (ARW in deg/sqrt(h) or VRW in m/s/sqrt(h)), ``noise_se`` and ``noise_units``.
    """
    y = as_signal(y, "y")
    rows = []
    for s in segments:
        fit = fit_noise(allan_deviation(y[s], rate, units=units, sensor=sensor))
        navigation = fit.navigation("N")
        if navigation is None:  # the fit was given the sensor and units, so never here
            raise InputError(f"no navigation units for a {sensor} in {units}")
        value, label = navigation
        scale = value / fit.coefficients["N"] if fit.coefficients["N"] > 0 else np.nan
        rows.append({"noise": value, "noise_se": fit.stderr["N"] * scale, "noise_units": label})
    return pd.DataFrame(rows)


# -- the table as a model ----------------------------------------------------------------------


class TableModel:
    """Per-plateau coefficients as functions of temperature, bound to a temperature record.

    Every tabulated coefficient (the bias and the AR weights) is fitted across the plateaus by
    a polynomial in temperature of degree ``degree`` (at most one less than the number of
    plateaus), weighted by the inverse squared standard errors.  The model is

        y[n] = b(T[n]) + sum_l a_l(T[n]) (y[n-l] - b(T[n-l])) + e[n].

    Parameters
    ----------
    table : DataFrame
        From :func:`segment_table`.
    temp : array-like
        The temperature column of the record the model is applied to.
    degree : int
        Polynomial degree in temperature.
    """

    def __init__(self, table: pd.DataFrame, temp: ArrayLike, degree: int = 2) -> None:
        self.temp = as_signal(temp, "temperature")
        deg = min(degree, len(table) - 1)
        t = table["temp_c"].to_numpy()
        order = sum(c.startswith("coef ") for c in table.columns)
        lags = [f"{OUTPUT}[n-{lag}]" for lag in range(1, order + 1)]
        self.bias = _wls_poly(t, table["bias"], table["bias_se"], deg)
        self.weights = [_wls_poly(t, table[f"coef {k}"], table[f"se {k}"], deg) for k in lags]
        self.lag_window_ = len(self.weights)

    def _coefficients(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bias and AR weights (one row per lag) at the temperatures ``t``."""
        return self.bias(t), np.array([a(t) for a in self.weights]).reshape(-1, len(t))

    def predict(self, y: ArrayLike) -> np.ndarray:
        """One-step prediction of ``y`` (the record's first ``len(y)`` samples)."""
        y = as_signal(y, "y")
        b, a = self._coefficients(self.temp[: len(y)])
        d = y - b
        out = b.copy()
        for lag in range(1, self.lag_window_ + 1):
            out[lag:] += a[lag - 1, lag:] * d[:-lag]
        out[: self.lag_window_] = np.nan
        return out

    def simulate(self, y_init: ArrayLike, n_steps: int) -> np.ndarray:
        """Free run after ``y_init`` (the record's first samples) for ``n_steps`` samples."""
        y0 = as_signal(y_init, "y_init")
        start, p = len(y0), self.lag_window_
        b, a = self._coefficients(self.temp[start - p : start + n_steps])
        d = np.r_[y0[start - p :] - b[:p], np.zeros(n_steps)]
        for n in range(p, p + n_steps):
            d[n] = sum(a[lag - 1, n] * d[n - lag] for lag in range(1, p + 1))
        return (d + b)[p:]


def _wls_poly(t: np.ndarray, values: pd.Series, se: pd.Series, degree: int) -> Polynomial:
    return Polynomial.fit(t, values.to_numpy(), degree, w=1.0 / se.to_numpy())


# -- held-out comparison -------------------------------------------------------------------------


def concatenate_plateaus(
    y: ArrayLike, temp: ArrayLike, segments: Sequence[slice]
) -> tuple[np.ndarray, np.ndarray, list[slice]]:
    """Join the plateaus of ``y`` and ``temp`` back to back; return them and their slices.

    Passed as ``segments`` to :meth:`FOSModel.fit`, the slices keep every lag inside its own
    plateau.
    """
    y, temp = as_signal(y, "y"), as_signal(temp, "temperature")
    ends = np.cumsum([0] + [s.stop - s.start for s in segments])
    runs = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]
    return (np.concatenate([y[s] for s in segments]),
            np.concatenate([temp[s] for s in segments]), runs)


def global_models(
    y: ArrayLike, temp: ArrayLike, segments: Sequence[slice], max_lag: int = 2, temp_lags: int = 1,
) -> dict[str, FOSModel]:
    """FOS models fitted across the plateaus ``segments``, with and without temperature.

    ``"fos_temp"`` offers the output lags ``y[n-1] .. y[n-max_lag]``, the temperature lags
    ``temp_c[n-0] .. temp_c[n-temp_lags]`` and the squared temperature as the user column
    ``temp_c_sq``, all linearly (a quadratic bias in temperature is in its span, and the
    model stays linear, so its free run is the fast AR recursion); ``"fos"`` offers the output
    lags alone.  Both are fitted on the plateaus placed back to back, each its own lag window
    (no lag reaches across a transition), and centred on those samples alone.

    Returns
    -------
    dict of str to FOSModel
        ``"fos_temp"`` (call it with ``{"temp_c": T, "temp_c_sq": T**2}``, see
        :func:`temperature_inputs`) and ``"fos"``.
    """
    yy, tt, runs = concatenate_plateaus(y, temp, segments)
    with_temp = FOSModel(max_lag=max_lag, exog_lags={TEMP: temp_lags}, columns=[TEMP_SQ])
    return {"fos_temp": with_temp.fit(yy, temperature_inputs(tt), segments=runs),
            "fos": FOSModel(max_lag=max_lag).fit(yy, segments=runs)}


def temperature_inputs(temp: ArrayLike) -> dict[str, np.ndarray]:
    """Return the inputs of a ``"fos_temp"`` model: ``temp_c`` and its square ``temp_c_sq``."""
    t = as_signal(temp, "temperature")
    return {TEMP: t, TEMP_SQ: t**2}


def held_out_comparison(
    y: ArrayLike,
    temp: ArrayLike,
    rate: float,
    segments: Sequence[slice],
    *,
    sensor: str | None = None,
    units: str | None = None,
    order: int = 1,
    max_lag: int = 2,
    temp_lags: int = 1,
    degree: int = 2,
    horizon_s: float = 30.0,
    n_starts: int = 10,
) -> pd.DataFrame:
    """Leave one plateau out: score three models fitted on the others on the one left out.

    * ``"table"``: :func:`segment_table` (AR(``order``)) on the training plateaus, as a
      :class:`TableModel` of polynomial degree ``degree``;
    * ``"fos_temp"`` and ``"fos"``: :func:`global_models` (the same ``max_lag``).

    Each is scored on the held-out plateau by the one-step MSE and by
    :func:`fosmodel.noise.metrics.outage_metrics` (``n_starts`` free runs of ``horizon_s`` seconds
    from the true past).

    Returns
    -------
    DataFrame
        One row per held-out plateau and model: ``held_out`` (plateau index), ``temp_c``,
        ``model``, ``mse``, ``outage_mse``, ``outage_position_error_m``, ``terms``.
    """
    y, temp = as_signal(y, "y"), as_signal(temp, "temperature")
    if len(segments) < 3:
        raise InputError(f"need at least 3 plateaus to leave one out, got {len(segments)}")
    first = max(order, max_lag, temp_lags)  # a plateau at the record's start: skip its lags
    rows = []
    for k, held in enumerate(segments):
        train = [s for j, s in enumerate(segments) if j != k]
        scored = slice(max(held.start, first), held.stop)
        fos = global_models(y, temp, train, max_lag, temp_lags)
        models: dict[str, TableModel | BoundModel] = {
            "table": TableModel(segment_table(y, temp, train, order), temp, degree),
            "fos_temp": BoundModel(fos["fos_temp"], temperature_inputs(temp)),
            "fos": BoundModel(fos["fos"], {})}
        for name, model in models.items():
            pred = model.predict(y)
            out = outage_metrics(model, y, rate, sensor, units, scored, horizon_s, n_starts,
                                 residual=(y - pred)[scored])
            terms = (f"AR({order}) table" if isinstance(model, TableModel)
                     else ", ".join(model.model.terms_))
            rows.append({"held_out": k, "temp_c": float(np.mean(temp[held])), "model": name,
                         "mse": one_step_mse(y, pred, scored),
                         "outage_mse": out["outage_mse"],
                         "outage_position_error_m": out["outage_position_error_m"],
                         "terms": terms})
    return pd.DataFrame(rows)
