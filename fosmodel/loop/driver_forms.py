"""Does a driver explain the slow residual?  Its physical forms, fitted beside a local level.

A sensor bias that follows a temperature does so slowly: through the driver
itself, its powers, its rate of change, and a first-order lag (a die follows
the air late).  Those *forms* (:mod:`fosmodel.core.derived`) are fitted to the
slow part of the output: means over blocks of about ``slow_s`` seconds, where
the fast noise has averaged out, while a stochastic level is allowed beside
them.  A local level at the block scale is an ARIMA(0,1,1) error, whose one-step
predictor is the exponential smoother of gain ``g`` (Harvey 1989, sec. 2.3), so the
regression with such an error is least squares on the smoother's innovations,
``y - s_g(y)`` on ``F - s_g(F)`` (Box and Jenkins' conditional sum of squares).
Beside ``g = 0`` a constant and a trend
of their own per session are tried: a driver that only does what a straight line
in time does is then no evidence of itself (a wander that happened to trend over
the fitting data fits any driver that swept meanwhile).  For each ``g`` of a grid the
forms (a base, the driver or one of its lags, and the degree of its powers) are
chosen by BIC, and the ``g`` with the lowest BIC wins.  So a driver that only
looks like a random walk (a spurious regression of two wandering series) is
judged on its increments, while one that explains most of the slow swing is
judged on its levels.  Sessions restart the smoother: each has its own constant,
its turn-on bias.

The test runs at two scales, the block and blocks four times longer: a bias
instability flat in Allan deviation hides a slow sweep's increments at the short
block but not at the long one.  The finding's p-value is the F test of the chosen
forms against none at the same ``g``, Bonferroni over the bases tried (the driver
and each of its lags) and over the scales: the degree,
the rate of change and the gain are nested refinements chosen by BIC, and a count of
every fit tried would take the same evidence as many times over.  The test only offers
the driver; the loop's judge, out of sample, decides.

References
----------
C. S. Bretherton, M. Widmann, V. I. Dymnikov, J. M. Wallace and I. Blade, "The
effective number of spatial degrees of freedom of a time-varying field", *Journal
of Climate* 12(7), 1999.
A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman Filter*,
Cambridge University Press, 1989, sections 2.3 and 7.2.
G. E. P. Box, G. M. Jenkins, *Time Series Analysis: Forecasting and Control*,
Holden-Day, 1976, section 7.1 (conditional least squares).
J. M. Wooldridge, *Econometric Analysis of Cross Section and Panel Data*, 2nd ed.,
MIT Press, 2010, section 10.5 (the within transformation).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
from scipy import stats

from ..core.derived import derive, parse, power_name, rate_name
from ..core.levels import smooth
from .diagnose import Finding
from .record import LoopRecord

#: Fewest blocks the fitting data are cut into: the block shrinks below ``slow_s`` to keep them.
MIN_BLOCKS = 200
#: The scales the driver is tested at, in blocks: the block, and blocks this many times longer.
#: A bias instability (flicker) flat in Allan deviation hides a slow sweep's increments at the
#: short block and not at the long one, where the sweep has moved further: an accelerometer's
#: 5e-4 m/s^2/C over a day's sweep read p 0.12 at 200 blocks and 5e-17 at 50.
SCALES = (1, 4)
#: Highest power of a driver offered: a quadratic is what a MEMS bias's temperature curve takes
#: (and what a cubic fitted on one session's range adds runs off beyond it: a session held out
#: that swept 4 C further lost 40 % at 30 min outages with one).
MAX_POWER = 2
#: First-order lags offered: this many time constants.
LAGS = 6
#: Gains of the block-scale level: time constants of this many blocks (and none: g = 0).
LEVEL_BLOCKS = (2.0, 6.0, 20.0, 60.0)
#: The "gain" that stands for a constant and a trend per session instead of a level.
TREND = -1.0
#: The block-scale errors a driver's forms are fitted beside: a constant per session, a
#: constant and a trend per session, a level of each of :data:`LEVEL_BLOCKS`.
GAINS = (0.0, TREND, *(1.0 / b for b in LEVEL_BLOCKS))
#: On short fitting data, a driver whose block means correlate with time this much or more
#: is tested without the trend rival too (:func:`time_like`).
TIME_LIKE = 0.5
#: The block-scale errors of that test: all of :data:`GAINS` but the trend.
FIRST_GAINS = tuple(g for g in GAINS if g != TREND)
#: A driver "varies" in the fitting data when the spread of its block means there is at
#: least this share of its spread over the whole record.
VARIES = 0.1


def short_fit(fit: Sequence[slice], rate: float, slow_s: float) -> bool:
    """Whether the fitting data are short for a driver: fewer than ``MIN_BLOCKS * slow_s`` s.

    There the blocks are shorter than ``slow_s`` (:func:`block_samples`), and a trend in
    time per session, fitted beside the driver's forms as a rival (:data:`TREND`), takes a
    driver that follows time for itself: ten minutes of a cooling die are one line.
    """
    return sum(s.stop - s.start for s in fit) < MIN_BLOCKS * slow_s * rate


def time_like(record: LoopRecord, fit: Sequence[slice], channel: str, slow_s: float) -> bool:
    """Whether the driver goes first: short fitting data over which it runs as time does.

    On short fitting data (:func:`short_fit`) whose driver's block means correlate with
    time at :data:`TIME_LIKE` or more, a function of time fitted there is an extrapolation
    and the measured driver the physics: the driver is then tested without the trend rival
    too (:data:`FIRST_GAINS`, at a stricter level, :func:`driver_first`).  Bartlett's
    bound (:func:`follows_time`) cannot say it there: over a few hundred blocks any series
    correlates with time by chance as far as two trends do.
    """
    if not short_fit(fit, record.rate, slow_s):
        return False
    means = block_means(record.channels[channel], fit, block_samples(fit, record.rate, slow_s))
    x = innovations(means, 0.0)
    t = innovations([np.arange(len(m), dtype=float) for m in means], 0.0)
    return len(x) >= 10 and bool(np.any(x)) and abs(float(np.corrcoef(x, t)[0, 1])) >= TIME_LIKE


def driver_first(target: np.ndarray, channel: str, forms: DriverForms,
                 alpha: float) -> Finding:
    """Test a time-like driver (:func:`time_like`) without the trend rival, at ``alpha ** 2``.

    The trend per session guards against a wander that trends with the driver over the
    fitting data; without it the test asks for the evidence of two tests at once (ten-minute
    controls, a random walk beside a cooling die temperature, read p 4e-5 to 5e-4 there; a
    bias that follows the die 1e-9 or less).  The evidence says it was tested so
    (``first``).
    """
    finding = slow_driver(target, channel, forms, alpha ** 2, FIRST_GAINS)
    finding.evidence["first"] = True
    return finding


def block_samples(fit: Sequence[slice], rate: float, slow_s: float) -> int:
    """Return the samples per block: the fitting data in :data:`MIN_BLOCKS` blocks.

    The longest blocks that leave enough of them: a driver's slow swing is clearest
    where the fast noise and the short wander of the bias have averaged out (a
    temperature's sensitivity shows in the means over minutes, not seconds).
    """
    total = sum(s.stop - s.start for s in fit)
    return max(1, total // MIN_BLOCKS)


def form_names(channel: str, centre: float, fit_s: float, block_s: float,
               rate: float, max_power: int = MAX_POWER, lags: int = LAGS,
               with_rate: bool = True) -> list[str]:
    """Return the forms offered for a driver: its powers, those of its lags, its rate of change.

    Powers 1 to ``max_power``.  The lags' time constants span three blocks to a tenth of the
    fitting data, geometrically (``lags`` of them; none and no rate of change with 0), each
    at least a sample; the rate of change (of the shortest lag) unless not ``with_rate``.
    """
    low, high = max(3 * block_s, 1.0 / rate), fit_s / 10
    taus = list(dict.fromkeys(float(f"{t:.2g}") for t in np.geomspace(low, high, lags))) \
        if high > low and lags else []
    names = [power_name(channel, p, centre) for p in range(1, max_power + 1)]
    for tau in taus:
        names += [power_name(channel, p, centre, tau_s=tau) for p in range(1, max_power + 1)]
    return names + ([rate_name(channel, taus[0])] if taus and with_rate else [])


def block_means(x: np.ndarray, parts: Sequence[slice], block: int) -> list[np.ndarray]:
    """Return the means of ``x`` (1-D, or a column each) over whole blocks, part by part."""
    out = []
    for s in parts:
        n = (s.stop - s.start) // block
        piece = x[s.start : s.start + n * block]
        out.append(piece.reshape(n, block, *x.shape[1:]).mean(axis=1))
    return out


def innovations(parts: list[np.ndarray], gain: float) -> np.ndarray:
    """Each part minus its one-step exponential smoother of ``gain``, or its mean or line.

    The first value of each part, where the smoother starts, is left out.  With ``gain``
    0 each part loses its mean; with :data:`TREND` its least-squares line in time.
    """
    out = [x - x.mean(axis=0) if gain == 0 else _detrended(x) if gain == TREND
           else (x - _smooth(x, gain))[1:] for x in parts if len(x) >= 3]
    return np.concatenate(out) if out else np.empty((0, *parts[0].shape[1:]))


def _detrended(x: np.ndarray) -> np.ndarray:
    t = np.arange(len(x), dtype=float)
    t -= t.mean()
    centred = x - x.mean(axis=0)
    slope = (t @ centred) / (t @ t)
    return centred - np.multiply.outer(t, slope)


def _smooth(x: np.ndarray, gain: float) -> np.ndarray:
    if x.ndim == 1:
        return smooth(x, gain)
    return np.column_stack([smooth(x[:, j], gain) for j in range(x.shape[1])])


class DriverForms:
    """A driver's forms, as block means over the fitting data: computed once per channel.

    They do not change while the model's residual does; each form is computed session
    by session and only its block means are kept.  ``max_power``, ``lags`` and
    ``with_rate`` are those of :func:`form_names`; ``block`` (samples) replaces
    :func:`block_samples`'s.
    """

    def __init__(self, record: LoopRecord, fit: Sequence[slice], slow_s: float,
                 max_power: int = MAX_POWER, lags: int = LAGS, block: int | None = None,
                 with_rate: bool = True) -> None:
        self.record, self.fit = record, tuple(fit)
        self.max_power, self.lags, self.with_rate = max_power, lags, with_rate
        self.block = block or block_samples(fit, record.rate, slow_s)
        self._forms: dict[str, tuple[list[str], list[np.ndarray]]] = {}

    def __call__(self, channel: str) -> tuple[list[str], list[np.ndarray]]:
        """Return the channel's form names and their block means (a column each, part by part)."""
        if channel not in self._forms:
            rec, fit = self.record, self.fit
            x = rec.channels[channel]
            centre = float(f"{np.concatenate([x[s] for s in fit]).mean():.4g}")
            names = form_names(channel, centre, sum(s.stop - s.start for s in fit) / rec.rate,
                               self.block / rec.rate, rec.rate, self.max_power, self.lags,
                               self.with_rate)
            columns = [np.column_stack([self._session_form(name, s) for name in names])
                       for s in fit]
            self._forms[channel] = names, [block_means(c, [slice(0, len(c))], self.block)[0]
                                           for c in columns]
        return self._forms[channel]

    def _session_form(self, name: str, part: slice) -> np.ndarray:
        """Return the form over one fitting part, computed from its session's start."""
        rec = self.record
        session = next(s for s in rec.sessions if s.start <= part.start < s.stop)
        values = derive(name, part.stop - session.start, rec.rate,
                        {k: v[session.start : part.stop] for k, v in rec.channels.items()}, {})
        return values[part.start - session.start :]


def slow_driver(target: np.ndarray, channel: str, forms: DriverForms,
                alpha: float, gains: Sequence[float] = GAINS) -> Finding:
    """Test whether the driver ``channel`` explains the slow part of ``target``.

    ``target`` is the output minus the model's compensation so far, over the record.  The
    test runs at each of :data:`SCALES` (the block, and blocks that many times longer) and
    keeps the scale of the smaller p-value, Bonferroni over the scales.  The forms are
    fitted beside each of the block-scale errors ``gains`` (:data:`GAINS`).  The evidence holds
    the chosen forms with their weights (``forms``), the block (s), the level's time
    constant at the block scale in blocks (``level_blocks``; None for a constant per
    session) and the share of the slow innovations the forms remove.
    """
    names, f_blocks = forms(channel)
    y_blocks = block_means(target, forms.fit, forms.block)
    evidence: dict = {"channel": channel, "block_s": forms.block / forms.record.rate,
                      "forms": [], "level_blocks": None, "share": 0.0}
    tests = [(scale, *_scale_test(_coarser(y_blocks, scale), _coarser(f_blocks, scale), names,
                                  forms.max_power, gains)) for scale in SCALES]
    scale, f, p, best = min(tests, key=lambda t: (t[2], t[0]))
    if best is None:
        return Finding("driver", 0.0, 1.0, alpha, evidence)
    gain, columns, coef, residual, sse0 = best
    sse = float(residual @ residual)
    evidence.update(block_s=forms.block * scale / forms.record.rate,
                    forms=[[names[j], float(w)] for j, w in zip(columns, coef)],
                    level_blocks=None if gain in (0, TREND) else 1.0 / gain,
                    trend=gain == TREND,
                    share=float(1 - sse / sse0) if sse0 > 0 else 0.0)
    return Finding("driver", f, min(1.0, p * len(SCALES)), alpha, evidence)


def _coarser(parts: list[np.ndarray], scale: int) -> list[np.ndarray]:
    """Return block means ``scale`` times longer: the means of ``scale`` consecutive ones."""
    if scale == 1:
        return parts
    return [x[: len(x) // scale * scale].reshape(len(x) // scale, scale, *x.shape[1:]).mean(axis=1)
            for x in parts]


def _scale_test(y_blocks: list[np.ndarray], f_blocks: list[np.ndarray], names: list[str],
                max_power: int, gains: Sequence[float]) -> tuple[float, float, tuple | None]:
    """Return the F statistic, its p-value and the best fit (:func:`_best_fit`) at one scale.

    The p-value is Bonferroni over the bases tried (the driver and each of its lags).
    """
    rate = bool(names) and (parse(names[-1]) or ("",))[0] == "rate"
    bases = (len(names) - rate) // max_power
    best = _best_fit(y_blocks, f_blocks, _models(bases, max_power, rate), gains)
    if best is None:
        return 0.0, 1.0, None
    _, columns, _, residual, sse0 = best
    k, sse = len(columns), float(residual @ residual)
    dof = effective_samples(residual) - k - 1
    f = ((sse0 - sse) / k) / (sse / dof) if sse > 0 and dof > 0 else 0.0
    p = min(1.0, float(stats.f.sf(f, k, dof)) * bases) if dof > 0 else 1.0
    return float(f), p, best


def _models(bases: int, max_power: int, rate: bool) -> list[list[int]]:
    """Return the column sets tried.

    Each base (the driver or one of its lags) with powers 1..p, p up to ``max_power``, with
    or without the rate of change (the last column, when :func:`form_names` has it).
    """
    extras = [[], [bases * max_power]] if rate else [[]]
    return [[j * max_power + q for q in range(p)] + extra for j in range(bases)
            for p in range(1, max_power + 1) for extra in extras]


def _best_fit(y_blocks: list[np.ndarray], f_blocks: list[np.ndarray],
              models: list[list[int]], gains: Sequence[float]) -> tuple | None:
    """Return the fit with the lowest BIC among the column sets ``models`` and ``gains``.

    The fit is ``(gain, columns, weights, residual, SSE with no form)``, or None
    when no form beats no form at all (a driver that does not vary, or explains nothing):
    a polynomial in one base, its degree chosen by BIC as the gain of the level is.
    """
    best, best_bic = None, math.inf
    for gain in gains:
        y, forms = innovations(y_blocks, gain), innovations(f_blocks, gain)
        if len(y) < 10 or np.ptp(y) == 0:
            continue
        y, forms = y - y.mean(), forms - forms.mean(axis=0)
        n, extra = len(y), int(gain != 0)  # a gain, or a trend per session
        sse0 = float(y @ y)
        null_bic = n * math.log(max(sse0 / n, 1e-300)) + extra * math.log(n)
        if null_bic < best_bic:
            best, best_bic = None, null_bic
        for columns in models:
            x = forms[:, columns]
            if np.ptp(x, axis=0).min() <= 1e-12 * (np.abs(x).max() + 1e-300):
                continue  # a form that does not vary here
            coef, *_ = np.linalg.lstsq(x, y, rcond=None)
            residual = y - x @ coef
            sse = float(residual @ residual)
            bic = n * math.log(max(sse / n, 1e-300)) + (len(columns) + extra) * math.log(n)
            if bic < best_bic:
                best, best_bic = (gain, columns, coef, residual, sse0), bic
    return best


def effective_samples(residual: np.ndarray) -> float:
    """Return the innovations' count as independent samples: ``n (1 - r) / (1 + r)``.

    ``r`` is their lag-one autocorrelation (none when it is negative).  A wander the
    forms and the level leave behind keeps its autocorrelation, and an F test counting
    every block as independent would take its fit to any swept driver for evidence (a
    spurious regression); this is the usual correction of the degrees of freedom for an
    AR(1) residual (Bretherton et al. 1999, eq. 31).
    """
    n = len(residual)
    zz = float(residual @ residual)
    r = max(0.0, float(residual[1:] @ residual[:-1]) / zz) if zz > 0 and n > 1 else 0.0
    return n * (1 - r) / (1 + r)


def innovations_of(target: np.ndarray, columns: Mapping[str, np.ndarray],
                   parts: Sequence[slice], block: int, gain: float,
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Return the centred innovations of ``target`` and of each form (a column each)."""
    y = innovations(block_means(target, parts, block), gain)
    f = innovations(block_means(np.column_stack(list(columns.values())), parts, block), gain)
    return y - y.mean() if len(y) else y, f - f.mean(axis=0) if len(f) else f


def refit_forms(target: np.ndarray, columns: Mapping[str, np.ndarray], parts: Sequence[slice],
                block: int, gain: float) -> dict[str, float]:
    """Return the weights of the given forms refitted on ``parts`` at the block-scale ``gain``.

    The forms stay; only their weights are fitted anew (least squares on the innovations),
    as :meth:`fosmodel.models.model.FOSModel.refit_weights` does for a model's terms.  A form
    that does not vary there keeps a weight of 0.
    """
    names = list(columns)
    y, f = innovations_of(target, columns, parts, block, gain)
    if len(y) < 2:
        return dict.fromkeys(names, 0.0)
    coef = np.linalg.lstsq(f, y, rcond=None)[0]
    return {n: float(w) for n, w in zip(names, coef)}


def forms_p(target: np.ndarray, columns: Mapping[str, np.ndarray], parts: Sequence[slice],
            block: int, gain: float, beside: Mapping[str, np.ndarray] | None = None) -> float:
    """Return the p-value of the forms ``columns`` on ``parts``: the F test against none.

    As :func:`slow_driver` tests them (the innovations at the block-scale ``gain``, their
    count as independent samples), but of forms already chosen: no count of bases tried.
    The forms ``beside`` (a compensation already in) are fitted in both models.  A large
    p-value says that these data do not tell the forms' weights from zero: over a steady
    ramp of the driver beside a trend, say, where the two are one line.
    """
    beside = dict(beside or {})
    y, f = innovations_of(target, {**beside, **columns}, parts, block, gain)
    k, j = len(columns), len(beside)
    if len(y) <= k + j + 2 or not np.any(y):
        return 1.0
    residual = _residual(y, f)
    sse = float(residual @ residual)
    sse0 = _sse(y, f[:, :j]) if j else float(y @ y)
    dof = effective_samples(residual) - k - j - 1
    if dof <= 0:
        return 1.0
    if sse <= 0:
        return 0.0
    return float(stats.f.sf(((sse0 - sse) / k) / (sse / dof), k, dof))


def _residual(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    return y - x @ np.linalg.lstsq(x, y, rcond=None)[0]


def _sse(y: np.ndarray, x: np.ndarray) -> float:
    residual = _residual(y, x)
    return float(residual @ residual)


def compensation_of(finding: Finding) -> dict[str, float]:
    """Return the forms and weights a driver finding chose."""
    return {str(name): float(w) for name, w in finding.evidence["forms"]}


def still(record: LoopRecord, forms: DriverForms, channel: str,
          target: np.ndarray) -> str | None:
    """Say so when ``channel`` follows the slow ``target`` but does not vary in the fitting data.

    "Follows": its block means over the whole record correlate with the target's beyond
    what two series of their autocorrelations would by chance (Bartlett's variance,
    two-sided 1 %).  For the report only: the loop chooses nothing by it.
    """
    block = forms.block
    x = np.concatenate(block_means(record.channels[channel], record.sessions, block))
    y = np.concatenate(block_means(target, record.sessions, block))
    fitted = np.concatenate(block_means(record.channels[channel], forms.fit, block))
    if len(x) < 10 or np.ptp(x) == 0 or np.ptp(y) == 0 or np.ptp(fitted) > VARIES * np.ptp(x):
        return None
    rho = float(np.corrcoef(x, y)[0, 1])
    if abs(rho) < _bartlett_bound(x, y):
        return None
    return (f"{channel} follows the slow residual but does not vary in the fitting segment: "
            f"give a record or sessions where it does (its block means correlate with the "
            f"output's at {rho:.2f} over the record)")


def follows_time(record: LoopRecord, parts: Sequence[slice], channel: str,
                 block: int) -> float | None:
    """Return how ``channel`` correlates with time over ``parts``, if beyond chance; else None.

    Its block means, each part's mean and time since its start removed, against that time;
    "beyond chance" as :func:`still` reads it (Bartlett's variance for two autocorrelated
    series, two-sided 1 %).  Over a steady sweep of the driver the two are one line: a
    trend in time fitted there cannot be told from the driver, and would run on where the
    driver holds still.
    """
    means = block_means(record.channels[channel], parts, block)
    x = innovations(means, 0.0)  # each part less its mean
    t = innovations([np.arange(len(m), dtype=float) for m in means], 0.0)
    if len(x) < 10 or not np.any(x):
        return None
    rho = float(np.corrcoef(x, t)[0, 1])
    return rho if abs(rho) >= _bartlett_bound(x, t) else None


def _bartlett_bound(x: np.ndarray, y: np.ndarray, lags: int = 20) -> float:
    """Return the 1 % two-sided bound of a correlation between two autocorrelated series."""
    n = len(x)
    rx, ry = _acf(x, min(lags, n // 4)), _acf(y, min(lags, n // 4))
    var = (1 + 2 * float(rx[1:] @ ry[1:])) / n
    return float(stats.norm.isf(0.005) * math.sqrt(max(var, 1.0 / n)))


def _acf(x: np.ndarray, lags: int) -> np.ndarray:
    xc = x - x.mean()
    c0 = float(xc @ xc)
    return np.array([1.0] + [float(xc[k:] @ xc[: len(x) - k]) / c0 for k in range(1, lags + 1)])


def forms_text(forms: Mapping[str, float]) -> str:
    """Put the forms chosen in words: ``lag 600 s, powers 1, 2; rate of change (lag 60 s)``."""
    powers: dict[str, list[int]] = {}
    extra = []
    for name in forms:
        found = parse(name) or ("",)
        if found[0] == "power":
            lag = parse(found[1])
            where = f"lag {float(lag[2]):g} s" if lag and lag[0] == "lowpass" else "as read"
            powers.setdefault(where, []).append(int(found[2]))
        elif found[0] == "rate":
            extra.append(f"rate of change (lag {float(found[2]):g} s)")
    parts = [f"{where}, power{'s' if len(p) > 1 else ''} {', '.join(map(str, sorted(p)))}"
             for where, p in powers.items()]
    return "; ".join(parts + extra)
