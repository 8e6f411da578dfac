"""One axis's bias against temperature: the forms chosen as the loop chooses a driver's.

A static sensor's slow bias follows its temperature: through the temperature itself or a
first-order lag of it (the bias follows the die late), in powers up to the degree asked,
beside a constant per session (its turn-on bias) or a wandering level.  The forms, the
degree and the level's gain are chosen by BIC on block means of the output, exactly as the
residual loop offers a driver's slow part (:func:`fosmodel.loop.driver_forms.slow_driver`,
without a trend in time: no firmware applies one), and kept where its F test against no
temperature effect holds at ``alpha``.  Then:

* a lag the grid chose is refined (its time constant by least squares within a factor two
  of the grid's), and kept only where it holds: the F test of the lag (one parameter, its
  time constant) against the temperature itself at the same powers, at ``alpha``;
* the weights are refitted about ``tref`` on the innovations of the chosen level
  (:func:`fosmodel.loop.driver_forms.innovations_of`), with a covariance robust to what
  autocorrelation the level leaves (Newey-West, the Bartlett lag window of Andrews 1991,
  :func:`fosmodel.loop.intervals.lag_window`) and Student intervals on the innovations'
  count as independent samples (:func:`fosmodel.loop.driver_forms.effective_samples`),
  Bonferroni over the axis's coefficients: its polynomial lies within them all at the
  confidence stated.

A model is applied with its base clipped to the range it was fitted over, as PX4's and
ArduPilot's firmware clip the temperature to ``TMIN``/``TMAX``.

References
----------
W. K. Newey and K. D. West, "A simple, positive semi-definite, heteroskedasticity and
autocorrelation consistent covariance matrix", *Econometrica* 55(3), 1987.
D. W. K. Andrews, "Heteroskedasticity and autocorrelation consistent covariance matrix
estimation", *Econometrica* 59(3), 1991.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import statsmodels.api as sm
from scipy import optimize, stats

from ..core.derived import derive, lowpass_name, parse, power_name
from ..loop.driver_forms import (
    LEVEL_BLOCKS,
    DriverForms,
    compensation_of,
    effective_samples,
    innovations_of,
    slow_driver,
)
from ..loop.intervals import lag_window
from ..loop.record import LoopRecord

#: The block-scale errors the forms are fitted beside: a wandering level of each of the loop's
#: time constants, started at each session's first block (its turn-on bias).
GAINS = tuple(1.0 / b for b in LEVEL_BLOCKS)
#: Lags offered on the grid before one is refined (the loop offers fewer: it tests many
#: channels; a calibration asks of one).
LAGS = 12


@dataclass(frozen=True)
class ThermalModel:
    """An axis's bias as a function of its temperature: weighted forms about ``tref``.

    Attributes
    ----------
    channel : str
        The temperature column.
    tref : float
        The centre of the powers (degC).
    forms : tuple of str
        Derived column names (:mod:`fosmodel.core.derived`): ``pow(<base>,k,<tref>)`` of the
        temperature or its lag ``lowpass(<temp>,<tau>s)``.
    weights : tuple of float
        Their weights, in the axis's units per degC^k.
    covariance : ndarray
        The weights' covariance.
    dof : float
        Degrees of freedom of their intervals.
    base_range : tuple of float
        The base's range over the fitting data, which it is clipped to.
    level_s : float, optional
        The time constant (s) of the wandering level the weights were fitted beside, over
        blocks of ``block_s`` (None: a constant per session).
    p_value : float
        The slow driver test's p-value of temperature against none.
    """

    channel: str
    tref: float
    forms: tuple[str, ...] = ()
    weights: tuple[float, ...] = ()
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    dof: float = math.inf
    base_range: tuple[float, float] = (-math.inf, math.inf)
    level_s: float | None = None
    block_s: float = 0.0
    p_value: float = 1.0

    @property
    def lag_s(self) -> float | None:
        """The thermal lag's time constant (s), or None when the bias follows the temperature."""
        for name in self.forms:
            found = parse(name)
            if found and found[0] == "power":
                base = parse(found[1])
                return float(base[2]) if base and base[0] == "lowpass" else None
        return None

    @property
    def powers(self) -> dict[int, float]:
        """The weight of each power of the base less ``tref``."""
        return {int(found[2]): w for name, w in zip(self.forms, self.weights)
                if (found := parse(name)) and found[0] == "power"}

    @property
    def degree(self) -> int:
        """The highest power (0: no temperature dependence)."""
        return max(self.powers, default=0)

    @property
    def firmware_form(self) -> bool:
        """Whether PX4's and ArduPilot's firmware evaluate it: powers of the temperature itself."""
        return self.lag_s is None

    def standard_errors(self) -> np.ndarray:
        """Return the weights' standard errors."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def intervals(self, confidence: float) -> np.ndarray:
        """Return the weights' intervals (rows of low, high), together at ``confidence``.

        Each at ``1 - (1 - confidence) / k`` for ``k`` weights (Bonferroni): the polynomial's
        coefficients all lie within theirs at ``confidence``.
        """
        share = (1 - confidence) / max(len(self.weights), 1)
        t = float(stats.t.ppf(1 - share / 2, max(self.dof, 1.0)))
        w, se = np.asarray(self.weights), self.standard_errors()
        return np.column_stack([w - t * se, w + t * se]) if len(w) else np.zeros((0, 2))

    def bias(self, temperature: np.ndarray, rate: float) -> np.ndarray:
        """Return the modelled bias over one session (its temperature from its start).

        The base (the temperature, or its lag started at the session's first value) is
        clipped to :attr:`base_range`.
        """
        temperature = np.asarray(temperature, dtype=float)
        if self.lag_s is not None:
            temperature = derive(lowpass_name(self.channel, self.lag_s), len(temperature), rate,
                                 {self.channel: temperature}, {})
        x = np.clip(temperature, *self.base_range) - self.tref
        return sum((w * x**k for k, w in self.powers.items()), np.zeros(len(x)))

    def describe(self) -> str:
        """``degree 2 in lowpass 310 s of temp_c, with a level``, or ``no temperature effect``."""
        if not self.forms:
            return "no temperature effect"
        base = self.channel if self.lag_s is None else f"{self.channel} lagged {self.lag_s:.3g} s"
        level = ("a constant per session" if self.level_s is None
                 else f"a level of {self.level_s:.4g} s")
        return f"degree {self.degree} in {base}, beside {level}"

    def to_dict(self, confidence: float) -> dict[str, Any]:
        """Return the model as JSON: its forms with their weights, errors and intervals."""
        intervals = self.intervals(confidence)
        return {"channel": self.channel, "tref": self.tref, "lag_s": self.lag_s,
                "degree": self.degree, "firmware_form": self.firmware_form,
                "base_range": list(self.base_range), "p_value": self.p_value,
                "level_s": self.level_s, "block_s": self.block_s,
                "forms": [{"name": n, "weight": w, "standard_error": float(se),
                           "interval": [float(lo), float(hi)]}
                          for n, w, se, (lo, hi) in zip(self.forms, self.weights,
                                                        self.standard_errors(), intervals)],
                "confidence": confidence, "dof": self.dof}


def fit_thermal(rec: LoopRecord, parts: Sequence[slice], channel: str, tref: float,
                degree: int, block: int, alpha: float, lags: bool = True,
                gains: Sequence[float] = GAINS) -> ThermalModel:
    """Choose and fit an axis's thermal model on the parts ``parts`` of ``rec`` (module doc).

    ``rec.y`` is the axis, ``rec.channels[channel]`` its temperature; ``degree`` the highest
    power offered and ``block`` the blocks (samples) of the slow part.  Without ``lags`` only
    powers of the temperature itself are offered: the firmware's form.
    """
    forms = DriverForms(rec, parts, 0.0, max_power=degree, lags=LAGS if lags else 0,
                        block=block, with_rate=False)
    finding = slow_driver(rec.y, channel, forms, alpha, gains)
    chosen = compensation_of(finding)
    if not chosen or finding.p_value >= alpha:  # the data do not tell temperature from none
        return ThermalModel(channel, tref, p_value=finding.p_value)
    block = round(finding.evidence["block_s"] * rec.rate)
    level = finding.evidence["level_blocks"]
    gain = 0.0 if level is None else 1.0 / level
    powers = sorted(int(f[2]) for n in chosen if (f := parse(n)) and f[0] == "power")
    tau = _lag_of(chosen)
    if tau is not None:
        tau = _refined(rec, parts, channel, tref, powers, tau, block, gain)
        lagged = [power_name(channel, p, tref, tau_s=tau) for p in powers]
        if not _holds(lagged, [power_name(channel, p, tref) for p in powers], rec, parts,
                      block, gain, alpha):
            tau = None
    names = [power_name(channel, p, tref, tau_s=tau) for p in powers]
    weights, covariance, dof = _weights(rec, parts, names, block, gain)
    base = np.concatenate([rec.channels[channel][s] for s in parts] if tau is None else
                          [c[:, 0] for c in _columns(rec, parts, [lowpass_name(channel, tau)])])
    return ThermalModel(channel, tref, tuple(names), tuple(weights), covariance, dof,
                        (float(base.min()), float(base.max())),
                        None if gain == 0 else block / gain / rec.rate, block / rec.rate,
                        finding.p_value)


def firmware_projection(model: ThermalModel, rec: LoopRecord,
                        parts: Sequence[slice]) -> ThermalModel:
    """Return the polynomial in the temperature itself nearest ``model`` over ``parts``.

    What the firmware can evaluate of a model with a lag: the powers of
    the temperature (up to the model's degree) whose least-squares fit to the model's bias,
    beside a constant per session, is closest over the fitting data.  The weights are a
    linear map of the model's, and so is their covariance.
    """
    if model.firmware_form:
        return model
    names = [power_name(model.channel, p, model.tref) for p in range(1, model.degree + 1)]
    f = [c - c.mean(axis=0) for c in _columns(rec, parts, model.forms)]
    g = [c - c.mean(axis=0) for c in _columns(rec, parts, names)]
    projection = np.linalg.lstsq(np.concatenate(g), np.concatenate(f), rcond=None)[0]
    weights = projection @ np.asarray(model.weights)
    base = np.concatenate([rec.channels[model.channel][s] for s in parts])
    return ThermalModel(model.channel, model.tref, tuple(names), tuple(float(w) for w in weights),
                        projection @ model.covariance @ projection.T, model.dof,
                        (float(base.min()), float(base.max())), model.level_s, model.block_s,
                        model.p_value)


def _lag_of(forms: dict[str, float]) -> float | None:
    for name in forms:
        found = parse(name)
        if found and found[0] == "power" and (base := parse(found[1])) and base[0] == "lowpass":
            return float(base[2])
    return None


def _columns(rec: LoopRecord, parts: Sequence[slice], names: Sequence[str]
             ) -> list[np.ndarray]:
    """Return the derived columns over each part, each from its session's start (not cached)."""
    out = []
    for part in parts:
        session = next(s for s in rec.sessions if s.start <= part.start < s.stop)
        channels = {k: v[session.start : part.stop] for k, v in rec.channels.items()}
        out.append(np.column_stack([derive(n, part.stop - session.start, rec.rate, channels, {})
                                    [part.start - session.start :] for n in names]))
    return out


def _innovations(rec: LoopRecord, parts: Sequence[slice], names: Sequence[str], block: int,
                 gain: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the innovations of the axis and of the forms ``names`` over ``parts``."""
    values = _columns(rec, parts, names)
    target = np.concatenate([rec.y[s] for s in parts])
    spans, start = [], 0
    for v in values:
        spans.append(slice(start, start + len(v)))
        start += len(v)
    full = np.concatenate(values)
    return innovations_of(target, {n: full[:, j] for j, n in enumerate(names)}, spans, block,
                          gain)


def _sse(rec: LoopRecord, parts: Sequence[slice], names: Sequence[str], block: int,
         gain: float) -> tuple[float, np.ndarray]:
    y, f = _innovations(rec, parts, names, block, gain)
    residual = y - f @ np.linalg.lstsq(f, y, rcond=None)[0]
    return float(residual @ residual), residual


def _refined(rec: LoopRecord, parts: Sequence[slice], channel: str, tref: float,
             powers: list[int], tau: float, block: int, gain: float) -> float:
    """Return the lag's time constant of least squares within a factor 2 of the grid's."""
    def sse(log_tau: float) -> float:
        names = [power_name(channel, p, tref, tau_s=math.exp(log_tau)) for p in powers]
        return _sse(rec, parts, names, block, gain)[0]

    low = math.log(max(tau / 2, 2.0 / rec.rate))
    best = optimize.minimize_scalar(sse, bounds=(low, math.log(2 * tau)), method="bounded",
                                    options={"xatol": 0.01})
    return float(f"{math.exp(best.x):.3g}")


def _holds(names: list[str], fewer: list[str], rec: LoopRecord, parts: Sequence[slice],
           block: int, gain: float, alpha: float) -> bool:
    """Whether the lagged forms ``names`` beat ``fewer``, the same powers of the temperature.

    The F test of one parameter (the lag's time constant) at ``alpha``, on the innovations'
    count as independent samples.
    """
    sse1, residual = _sse(rec, parts, names, block, gain)
    sse0, _ = _sse(rec, parts, fewer, block, gain)
    dof = effective_samples(residual) - len(names) - 2
    if dof <= 0 or sse1 <= 0:
        return False
    return float(stats.f.sf((sse0 - sse1) / (sse1 / dof), 1, dof)) < alpha


def _weights(rec: LoopRecord, parts: Sequence[slice], names: Sequence[str], block: int,
             gain: float) -> tuple[list[float], np.ndarray, float]:
    """Return the weights of ``names``, their HAC covariance and the intervals' dof."""
    y, f = _innovations(rec, parts, names, block, gain)
    ols = sm.OLS(y, f).fit()
    lags = lag_window(ols.resid)
    robust = sm.OLS(y, f).fit(cov_type="HAC", cov_kwds={"maxlags": lags})
    dof = max(effective_samples(np.asarray(ols.resid)) - len(names) - 1, 1.0)
    return ([float(w) for w in robust.params], np.asarray(robust.cov_params(), dtype=float),
            float(dof))

