"""Residual diagnostics: what a fitted model left behind, one statistical test at a time.

Every test returns a :class:`Finding`: its statistic, a p-value (with the
multiple comparisons made inside the test accounted for, by Bonferroni), the
level it is compared with, the evidence a user needs to act on it, and the
arrays of its figure.  The residual passed in is the one-step residual of the
current model over the samples it may look at (never the prediction segment).

=============  ==============================================================  ============
test           statistic                                                       points to
=============  ==============================================================  ============
whiteness      Ljung-Box Q (statsmodels)                                        (nothing)
periodic       least-squares spectrum peak over its local level, refined by     periodic
               a FOS search over sinusoids between the FFT bins
aux            cross-correlation with each other channel and its square,       aux
               lags 0..K, Bartlett variance
nonlinear      F test of lagged-output squares and cross-products (RESET)      nonlinear
trend          F test of a polynomial / exponential warm-up in time            drift
wander         CUSUM against the Brownian bridge, Newey-West long-run var      level
step           the same CUSUM, batch-means long-run variance less the shift    step
allan          Allan deviation at long tau over its white-noise value (chi2)   (nothing)
=============  ==============================================================  ============

References
----------
.. [1] M. El-Diasty, A. El-Rabbany and S. Pagiatakis, "Stochastic Characteristics of
   Temperature-Dependent MEMS-Based Inertial Sensor Error", Proceedings of the ION
   National Technical Meeting, San Diego, CA, 2007.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import allantools
import numpy as np
from scipy import stats
from scipy.ndimage import median_filter
from scipy.signal import ZoomFFT, zoom_fft

from ..core.fos import StopRule, fos_search

ALPHA = 1e-3
# Records over BLOCKED_ROWS have the nonlinearity test's Gram matrix accumulated over blocks of
# BLOCK rows; shorter ones build the matrix of products as before (bit-identical results).
BLOCKED_ROWS = 2**21
BLOCK = 2**16
ZOOM_BLOCK = 2**20  # samples per chirp z-transform of a long residual (refine_frequency)
#: Batches of the residual whose means give the step test's long-run variance: enough for an
#: estimate with 29 degrees of freedom (Schmeiser 1982's 10 to 30), few enough that each is
#: longer than the wander a level leaves (48 min batches over a day at 1 Hz).
STEP_BATCHES = 30
#: Largest lag-one correlation of the batch means the step test's variance is widened for:
#: beyond it the batch means are a random walk and no factor is trustworthy (a factor 19).
MAX_BATCH_CORRELATION = 0.9
#: Most values of a finding's figure arrays: a figure shows no more, and record-long arrays
#: kept in every finding would hold gigabytes of a day's residual.
PLOT_POINTS = 20_000


@dataclass
class Finding:
    """The outcome of one diagnostic test.

    Attributes
    ----------
    test : str
        Name of the test (``whiteness``, ``periodic``, ``aux``, ``nonlinear``, ``trend``,
        ``step``, ``allan``).
    statistic, p_value : float
        The test statistic and its p-value, corrected for the comparisons inside the test.
    alpha : float
        The level the p-value is compared with.
    evidence : dict
        JSON-serialisable details (frequency, channel and lag, form of a trend...).
    plot : dict
        Arrays for the test's figure, each at most :data:`PLOT_POINTS` long (or one value
        per second of the residual): thinned, block means or bin means of the test's own.
    """

    test: str
    statistic: float
    p_value: float
    alpha: float
    evidence: dict
    plot: dict = field(default_factory=dict, repr=False)

    @property
    def fired(self) -> bool:
        """Whether the test fired: its p-value below ``alpha``."""
        return bool(self.p_value < self.alpha)

    def to_dict(self) -> dict:
        """Return the finding as a JSON-ready dict (without the plot data)."""
        return {"test": self.test, "statistic": float(self.statistic),
                "p_value": float(self.p_value), "alpha": self.alpha, "fired": self.fired,
                "evidence": self.evidence}


def _bonferroni(p: float, count: int) -> float:
    return float(min(1.0, p * count))


def thinned(x: np.ndarray, points: int = PLOT_POINTS) -> np.ndarray:
    """Every k-th value of ``x``, at most ``points`` of them: a smooth curve's own values."""
    return np.array(x[:: -(-len(x) // points) or 1])  # a copy: a view would keep x alive


def block_means(x: np.ndarray, points: int = PLOT_POINTS) -> np.ndarray:
    """Means of consecutive blocks of ``x``, at most ``points`` of them: a noisy curve's level.

    A remainder shorter than a block is left out.
    """
    return _means_of_blocks(x, max(1, -(-len(x) // points)))


def second_means(time: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the times and means of ``x`` over consecutive one-second blocks of ``time``."""
    step = max(1, round(1.0 / float(time[1] - time[0]))) if len(time) > 1 else 1
    return np.array(time[: len(x) // step * step : step]), _means_of_blocks(x, step)


def _means_of_blocks(x: np.ndarray, step: int) -> np.ndarray:
    """Means of consecutive blocks of ``step`` values of ``x`` (new; a remainder left out)."""
    return x[: len(x) // step * step].reshape(-1, step).mean(axis=1)


def bin_means(x: np.ndarray, r: np.ndarray, bins: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``x`` and ``r`` in quantile bins of ``x``.

    A quantised ``x`` repeats edges, whose bins drop.
    """
    edges = np.unique(np.quantile(x, np.linspace(0, 1, bins + 1)))
    idx = np.searchsorted(edges, x, side="right")  # one array of x's length, worked in place
    idx -= 1
    np.clip(idx, 0, max(len(edges) - 2, 0), out=idx)
    count = np.bincount(idx)
    kept = count > 0
    return (np.bincount(idx, weights=x)[kept] / count[kept],
            np.bincount(idx, weights=r)[kept] / count[kept])


# -- whiteness ------------------------------------------------------------------------------


def autocorrelation(x: np.ndarray, nlags: int) -> np.ndarray:
    """Return the sample autocorrelation at lags ``0 .. nlags``, as statsmodels' ``acf``.

    Mean removed, sums over N, by one dot product per lag: for the few lags the tests read
    this beats an FFT of a long record several times.
    """
    xc = np.asarray(x, dtype=float) - np.mean(x)
    n = len(xc)
    c0 = float(xc @ xc)
    if c0 == 0:
        return np.r_[1.0, np.zeros(nlags)]
    return np.array([1.0] + [float(xc[k:] @ xc[: n - k]) / c0 for k in range(1, nlags + 1)])



def whiteness(residual: np.ndarray, lags: int = 20, alpha: float = ALPHA) -> Finding:
    """Ljung-Box test over ``lags`` lags, with the residual ACF against its 95 % band.

    ``Q = N (N + 2) sum_k rho_k^2 / (N - k)`` against chi2(lags), as statsmodels'
    ``acorr_ljungbox`` computes it, but from the FFT autocorrelation: its own
    uses a direct correlation, O(N^2), minutes on a record of a million samples.
    """
    n = len(residual)
    nlags = int(min(100, n // 4))
    rho = autocorrelation(residual, max(nlags, lags))
    k = np.arange(1, lags + 1)
    q = float(n * (n + 2) * np.sum(rho[k] ** 2 / (n - k)))
    return Finding("whiteness", q, float(stats.chi2.sf(q, lags)), alpha, {"lags": lags},
                   {"acf": rho[: nlags + 1], "band": 1.96 / math.sqrt(n)})


# -- periodic content -----------------------------------------------------------------------


def least_squares_spectrum(x: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Variance fraction explained by a sinusoid at each Fourier frequency (El-Diasty et al. 2007).

    For equally spaced samples the sinusoids at the Fourier frequencies ``k/T``
    are orthogonal to the mean and to each other, so the least-squares (Lomb-
    Scargle, floating mean) spectrum there is the normalised periodogram,
    ``2 |X_k|^2 / (N sum (x - mean)^2)``, computed by FFT.  (scipy's
    ``lombscargle(..., normalize=True, floating_mean=True)`` gives the same
    values; it costs N x M trigonometric evaluations.)
    """
    xc = x - x.mean()
    n = len(xc)
    k = np.arange(1, (n - 1) // 2 + 1)
    # numpy's FFT, not scipy's: scipy's is twice as fast on a length with a large prime
    # factor, but keeps the plan of each length it meets (66 MB after a day's residual)
    power = np.abs(np.fft.rfft(xc)[k]) ** 2
    return k * rate / n, 2.0 * power / (n * float(xc @ xc))


def periodic(
    residual: np.ndarray, time: np.ndarray, rate: float, alpha: float = ALPHA,
    fmin_hz: float | None = None, window: int = 101,
) -> Finding:
    """Find the strongest spectral peak against the local level of the spectrum.

    Under a locally white residual, ``s_k / (local median / ln 2)`` is a unit
    exponential variable, so a peak's false-alarm probability over the ``M``
    frequencies tested is ``1 - (1 - exp(-z))^M``.  Frequencies below
    ``fmin_hz`` (default: 5 FFT bins) are left to the trend tests.  The peak's
    frequency is refined between the bins by :func:`refine_frequency`.
    """
    freqs, s = least_squares_spectrum(residual, rate)
    fmin = 5 * rate / len(residual) if fmin_hz is None else fmin_hz
    level = median_filter(s, size=window, mode="mirror") / math.log(2.0)  # not "nearest": it
    # would fill the edge windows with copies of one value
    z = np.where(freqs >= fmin, s / level, 0.0)
    k = int(np.argmax(z))
    m = int(np.count_nonzero(freqs >= fmin))
    fap = float(-np.expm1(m * np.log1p(-math.exp(-z[k])))) if z[k] > 0 else 1.0
    f_hat = refine_frequency(residual, time, float(freqs[k]), rate)
    amplitude = math.sqrt(2.0 * s[k] * float(np.var(residual)))
    return Finding("periodic", float(z[k]), fap, alpha,
                   {"freq_hz": f_hat, "freq_fft_hz": float(freqs[k]), "power": float(s[k]),
                    "amplitude": amplitude},
                   {"freqs": block_means(freqs), "spectrum": block_means(s)})


def refine_frequency(
    x: np.ndarray, time: np.ndarray, f0: float, rate: float, span_bins: float = 1.0,
    step_bins: float = 0.02, phases: int = 16,
) -> float:
    """Return the frequency near ``f0`` of the single sinusoid FOS selects first.

    The candidates are ``cos(2 pi f t + phi)`` for ``f`` within ``span_bins``
    FFT bins of ``f0`` in steps of ``step_bins`` bins and ``phases`` phases in
    [0, pi): one term can then match a sinusoid's frequency and phase, which a
    cosine or a sine alone at a nearby frequency would trade against each
    other.  Their means and mean products are geometric sums in closed form
    (:class:`_SinusoidCorrelations`); their correlations with ``x`` come from
    one zoom FFT (chirp z-transform) over the evenly spaced grid.
    """
    n = len(x)
    grid = f0 + np.arange(-span_bins, span_bins + step_bins / 2, step_bins) * rate / n
    grid = grid[(grid > 0) & (grid < rate / 2)]
    xc = x - x.mean()
    # sum_n x e^{i w t_n} = e^{i w t_0} conj(sum_n x e^{-2 pi i f n / rate}) for real x
    sums = np.exp(2j * np.pi * grid * time[0]) * np.conj(_zoom(xc, grid, rate))
    phi = np.arange(phases) * np.pi / phases
    omega = np.repeat(2 * np.pi * grid, phases)
    phase = np.tile(phi, len(grid))
    # mean of x cos(wt + phi) = Re(e^{i phi} sum x e^{i w t}) / n
    target = (np.repeat(sums, phases) * np.exp(1j * phase)).real / n
    corr = _SinusoidCorrelations(omega, phase, time[0], 1.0 / rate, n, target,
                                 float(xc @ xc) / n)
    res = fos_search(corr, StopRule("max_terms", max_terms=1), intercept=True)
    return float(omega[res.support[0]] / (2 * np.pi)) if len(res.support) else f0


def _zoom(x: np.ndarray, grid: np.ndarray, rate: float) -> np.ndarray:
    """``sum_n x[n] exp(-2 pi i f n / rate)`` at each ``f`` of the evenly spaced ``grid``.

    One chirp z-transform of the record, or of ``ZOOM_BLOCK`` samples at a time
    when it is longer, each block's sums turned by its start's phase: the
    transform of a whole long record takes several arrays of its length, and
    scipy keeps the FFT plan of every length it has seen (a day's residual
    would leave hundreds of megabytes behind).  The same sums, to rounding.
    """
    band, m = [grid[0], grid[-1]], len(grid)
    if len(x) <= ZOOM_BLOCK:
        return zoom_fft(x, band, m=m, fs=rate, endpoint=True)
    transform = ZoomFFT(ZOOM_BLOCK, band, m=m, fs=rate, endpoint=True)
    total = np.zeros(m, dtype=complex)
    for start in range(0, len(x), ZOOM_BLOCK):
        block = x[start : start + ZOOM_BLOCK]
        if len(block) < ZOOM_BLOCK:  # zeros add nothing to the sums
            block = np.r_[block, np.zeros(ZOOM_BLOCK - len(block))]
        total += np.exp(-2j * np.pi * grid * start / rate) * transform(block)
    return total


def _exp_sum(omega: np.ndarray, t0: float, dt: float, n: int) -> np.ndarray:
    """``sum_j exp(i omega t_j)`` for ``t_j = t0 + j dt``, j < n (a Dirichlet kernel)."""
    theta = omega * dt
    half = np.sin(theta / 2)
    safe = np.abs(half) > 1e-12  # elsewhere theta is a multiple of 2 pi: every term is equal
    ratio = np.sin(n * theta / 2) / np.where(safe, half, 1.0)
    formula = np.exp(1j * (omega * t0 + theta * (n - 1) / 2)) * ratio
    return np.where(safe, formula, n * np.exp(1j * omega * t0))


class _SinusoidCorrelations:
    """FOS correlations of candidates ``cos(omega_c t + phase_c)``, from closed forms.

    ``mean(cos a cos b) = Re[e^{i(pa - pb)} S(wa - wb) + e^{i(pa + pb)} S(wa + wb)] / 2n``
    with ``S`` the geometric sum :func:`_exp_sum`; only the target correlations
    (given) need the samples.
    """

    def __init__(self, omega: np.ndarray, phase: np.ndarray, t0: float, dt: float, n: int,
                 target: np.ndarray, y_mean_sq: float) -> None:
        self.omega, self.phase, self.t0, self.dt, self.n_samples = omega, phase, t0, dt, n
        self.target, self.y_mean, self.y_mean_sq = target, 0.0, y_mean_sq
        self.means = (np.exp(1j * phase) * _exp_sum(omega, t0, dt, n)).real / n
        self.diag = 0.5 + 0.5 * (np.exp(2j * phase) * _exp_sum(2 * omega, t0, dt, n)).real / n

    def column(self, j: int) -> np.ndarray:
        """Return the mean products of candidate ``j`` with every candidate (closed forms)."""
        w, p, n = self.omega, self.phase, self.n_samples
        diff = np.exp(1j * (p - p[j])) * _exp_sum(w - w[j], self.t0, self.dt, n)
        total = np.exp(1j * (p + p[j])) * _exp_sum(w + w[j], self.t0, self.dt, n)
        return 0.5 * (diff.real + total.real) / n


# -- auxiliary channels ---------------------------------------------------------------------


class AuxChannels:
    """Other channels of a record, standardised (as they are and squared) with their ACF.

    They do not change while a model's residual does: a loop that tests
    several residuals against the same channels prepares them once.
    """

    def __init__(self, channels: Mapping[str, np.ndarray], acf_lags: int = 50) -> None:
        self.acf_lags = acf_lags
        self.forms: dict[str, dict[bool, tuple[np.ndarray, np.ndarray] | None]] = {}
        for name, x in channels.items():
            self.forms[name] = {}
            for square in (False, True):
                z = _standard((x - x.mean()) ** 2 if square else x)
                self.forms[name][square] = None if z is None else (
                    z, autocorrelation(z, acf_lags)[1:])


def aux_correlation(
    residual: np.ndarray, channels: Mapping[str, np.ndarray] | AuxChannels, max_lag: int = 10,
    alpha: float = ALPHA, acf_lags: int = 50,
) -> list[Finding]:
    """Cross-correlation of the residual with each channel and its square at lags 0..K.

    ``rho_k = corr(r[n], x[n-k])``; its variance under independence is
    Bartlett's ``(1 + 2 sum_j rho_rr(j) rho_xx(j)) / N``, so a slowly varying
    channel (a temperature) is not flagged because of a residual that is not
    quite white.  One finding per channel, Bonferroni over all channels, both
    forms and all lags.  ``channels`` may be prepared (:class:`AuxChannels`).
    """
    if not isinstance(channels, AuxChannels):
        channels = AuxChannels(channels, acf_lags)
    count = max(1, 2 * (max_lag + 1) * len(channels.forms))
    r = _standard(residual)
    r_acf = None if r is None else autocorrelation(r, channels.acf_lags)[1:]
    out = []
    for name, forms in channels.forms.items():
        best = (0.0, 0, 0.0, False)  # z, lag, rho, square
        rhos = {}
        for square, prepared in forms.items():
            if prepared is None or r is None:
                continue
            z, z_acf = prepared
            rho = np.array([r[max_lag:] @ z[max_lag - k : len(z) - k] for k in range(max_lag + 1)])
            rho /= len(r) - max_lag
            var = (1 + 2 * float(r_acf @ z_acf)) / len(r)
            zs = np.abs(rho) / math.sqrt(max(var, 1.0 / len(r)))
            rhos[square] = rho
            k = int(np.argmax(zs))
            if zs[k] > best[0]:
                best = (float(zs[k]), k, float(rho[k]), square)
        p = _bonferroni(2 * stats.norm.sf(best[0]), count)
        out.append(Finding("aux", best[0], p, alpha,
                           {"channel": name, "lag": best[1], "rho": best[2], "square": best[3]},
                           {"lags": np.arange(max_lag + 1), "rho": rhos.get(False),
                            "rho_square": rhos.get(True),
                            "band": 1.96 / math.sqrt(len(residual))}))
    return out


def _standard(x: np.ndarray) -> np.ndarray | None:
    sd = float(np.std(x))
    return None if sd == 0 else (x - x.mean()) / sd


# -- nonlinearity ---------------------------------------------------------------------------


def nonlinearity(residual: np.ndarray, lagged: np.ndarray, alpha: float = ALPHA) -> Finding:
    """Test (RESET-style F) whether squares and products of lagged outputs explain the residual.

    ``lagged`` holds ``y[n-1] .. y[n-L]`` row by row (aligned with ``residual``);
    the restricted model has the constant and the lags, the full one adds all
    ``L (L+1) / 2`` products.  Both fits come from one Gram matrix of the
    centred, standardised columns (the restricted one is its leading block).
    """
    lags = lagged.shape[1]
    iu = np.triu_indices(lags)
    r = residual - residual.mean()
    if len(lagged) > BLOCKED_ROWS:
        gram, g, product = _blocked_product_gram(lagged, r, iu)
    else:
        gram, g, product = _product_gram(lagged, r, iu)
    total = float(r @ r)
    diag = np.diag(gram)
    scale = np.sqrt(np.where(diag > 0, diag, 1.0))  # standardise in the normal equations
    gram, g = gram / np.outer(scale, scale), g / scale
    coef = np.linalg.lstsq(gram, g, rcond=None)[0]
    rss1 = total - float(g @ coef)
    rss0 = total - float(g[:lags] @ np.linalg.lstsq(gram[:lags, :lags], g[:lags], rcond=None)[0])
    q = len(iu[0])
    dof = len(lagged) - 1 - lags - q
    f = ((rss0 - rss1) / q) / (rss1 / dof)
    strongest = int(np.argmax(np.abs(coef[lags:])))  # on standardised products
    i, j = iu[0][strongest] + 1, iu[1][strongest] + 1
    centres, means = bin_means(product(strongest), residual)
    return Finding("nonlinear", float(f), float(stats.f.sf(f, q, dof)), alpha,
                   {"products": int(q), "max_lag": int(lags),
                    "strongest": f"y[n-{i}]^2" if i == j else f"y[n-{i}]*y[n-{j}]"},
                   {"product": centres, "mean_residual": means})


def _product_gram(lagged: np.ndarray, r: np.ndarray, iu: tuple) -> tuple:
    """Gram matrix and ``X' r`` of the centred lags and their centred products, one pass.

    Returns ``(gram, X' r, product)``, ``product(k)`` the k-th centred product column.
    """
    lags = lagged.shape[1]
    x = np.empty((len(lagged), lags + len(iu[0])), order="F")  # columns built one at a time
    for k in range(lags):
        x[:, k] = lagged[:, k] - lagged[:, k].mean()
    for k, (i, j) in enumerate(zip(*iu), start=lags):
        np.multiply(x[:, i], x[:, j], out=x[:, k])
        x[:, k] -= x[:, k].mean()
    return x.T @ x, x.T @ r, lambda k: x[:, lags + k].copy()  # a copy: x is freed after


def _blocked_product_gram(lagged: np.ndarray, r: np.ndarray, iu: tuple) -> tuple:
    """:func:`_product_gram` accumulated over blocks of ``BLOCK`` rows, for long records.

    The matrix of products would hold ``L (L + 3) / 2`` columns of the record (a
    gigabyte for a day at 200 Hz); a block's stays in the cache.  Equal to the
    one-pass matrices within rounding.
    """
    n = len(lagged)
    means = lagged.mean(axis=0)
    blocks = [(lo, min(lo + BLOCK, n)) for lo in range(0, n, BLOCK)]

    def centred(lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        x = lagged[lo:hi] - means
        return x, x[:, iu[0]] * x[:, iu[1]]

    product_means = sum(centred(lo, hi)[1].sum(axis=0) for lo, hi in blocks) / n
    size = lagged.shape[1] + len(iu[0])
    gram, g = np.zeros((size, size)), np.zeros(size)
    for lo, hi in blocks:
        x, products = centred(lo, hi)
        block = np.hstack([x, products - product_means])
        gram += block.T @ block
        g += block.T @ r[lo:hi]

    def product(k: int) -> np.ndarray:
        i, j = iu[0][k], iu[1][k]
        return (lagged[:, i] - means[i]) * (lagged[:, j] - means[j]) - product_means[k]

    return gram, g, product


# -- drift and steps ------------------------------------------------------------------------

def trend(residual: np.ndarray, time: np.ndarray, alpha: float = ALPHA) -> Finding:
    """F test of a low-frequency trend: polynomial or exponential warm-up, best by BIC.

    The exponential's time constant is scanned on a log grid from 1/50 of the
    span to the span; the p-value is Bonferroni-corrected for every form and
    time constant tried.  The evidence gives the best form and, whatever that
    form, the time constant of the best exponential one.  Each fit needs only
    the dot products of its centred columns (``RSS = RSS0 - g' G^-1 g``).
    """
    n, span = len(residual), float(time[-1] - time[0])
    t0 = float(time[0])
    r = residual - residual.mean()
    rss0 = float(r @ r)
    t, t2 = _centred((time - t0) / span), _centred(((time - t0) / span) ** 2)
    base = {"t": (t, float(t @ r)), "t2": (t2, float(t2 @ r))}
    taus = np.geomspace(span / 50, span, 30)
    fits = [_trend_fit("linear", None, [base["t"]], rss0, n),
            _trend_fit("quadratic", None, [base["t"], base["t2"]], rss0, n)]
    for tau in taus:  # each exponential once: both of its forms need only its dot products
        e = _centred(np.exp(-(time - t0) / tau))
        fits.append(_trend_fit("exponential", tau, [(e, float(e @ r))], rss0, n))
        fits.append(_trend_fit("linear+exponential", tau, [base["t"], (e, float(e @ r))],
                               rss0, n))
    bic, form, tau, rss = min(fits, key=lambda f: f[0])
    best_tau = min((f for f in fits if f[2] is not None), key=lambda f: f[0])[2]
    chosen = [base[name] for name in _POLYNOMIAL[form]]
    if tau is not None:
        e = _centred(np.exp(-(time - t0) / tau))
        chosen.append((e, float(e @ r)))
    weights = _trend_weights(chosen)[1]
    curve = residual.mean() + sum(w * column for w, (column, _) in zip(weights, chosen))
    q = len(chosen)
    f = ((rss0 - rss) / q) / (rss / (n - q - 1))
    p = _bonferroni(float(stats.f.sf(f, q, n - q - 1)), len(fits))
    return Finding("trend", float(f), p, alpha,
                   {"form": form, "tau_s": float(best_tau),
                    "range": float(curve.max() - curve.min()),
                    "bic_gain": float(n * math.log(rss0 / n) - bic)},
                   {"time": thinned(time), "fit": thinned(curve),
                    **dict(zip(("second", "mean"), second_means(time, residual)))})


#: The polynomial columns of each trend form (the exponential ones add their exponential).
_POLYNOMIAL = {"linear": ("t",), "quadratic": ("t", "t2"), "exponential": (),
               "linear+exponential": ("t",)}


def _trend_weights(cols: list) -> tuple[np.ndarray, np.ndarray]:
    """Return ``g`` and the least-squares weights ``G^-1 g`` of ``[(column, column . r), ...]``."""
    gram = np.array([[float(a @ b) for b, _ in cols] for a, _ in cols])
    g = np.array([gr for _, gr in cols])
    return g, np.linalg.lstsq(gram, g, rcond=None)[0]


def _trend_fit(form: str, tau: float | None, cols: list, rss0: float, n: int) -> tuple:
    """Return ``(BIC, form, tau, RSS)`` of the centred columns ``[(column, column . r), ...]``.

    ``RSS = RSS0 - g' G^-1 g``.
    """
    g, weights = _trend_weights(cols)
    rss = rss0 - float(g @ weights)
    k = len(cols) + (tau is not None)
    return (n * math.log(max(rss, 1e-300) / n) + k * math.log(n), form, tau, rss)


def _centred(x: np.ndarray) -> np.ndarray:
    return x - x.mean()


def mean_stability(residual: np.ndarray, alpha: float = ALPHA) -> Finding:
    """CUSUM test of a stable mean against a wandering one: evidence of a level.

    ``D = max |S_k| / (sigma_LR sqrt(N))`` against the supremum of a Brownian bridge, the
    long-run variance from a Bartlett kernel over a Newey-West bandwidth of a few dozen
    lags: a mildly coloured residual does not fire it, a mean that wanders over minutes,
    a random walk's or a step's, does (the KPSS idea, Kwiatkowski et al. 1992, with
    Kolmogorov's tail for its supremum).  Which of the two it is the step test says.

    References
    ----------
    D. Kwiatkowski, P. C. B. Phillips, P. Schmidt and Y. Shin, "Testing the null hypothesis
    of stationarity against the alternative of a unit root", *Journal of Econometrics*
    54, 1992.
    """
    n = len(residual)
    r = residual - residual.mean()
    cusum = np.cumsum(r)
    bandwidth = int(4 * (n / 100) ** (2 / 9))
    gamma = [float(r[k:] @ r[: n - k]) / n for k in range(bandwidth + 1)]
    lrv = gamma[0] + 2 * sum((1 - k / (bandwidth + 1)) * gamma[k] for k in range(1, bandwidth + 1))
    d = float(np.max(np.abs(cusum)) / math.sqrt(max(lrv, 1e-300) * n))
    return Finding("wander", d, float(stats.kstwobign.sf(d)), alpha, {"bandwidth": bandwidth})


def change_point(residual: np.ndarray, time: np.ndarray, alpha: float = ALPHA) -> Finding:
    """CUSUM test for a shift of the mean, against the supremum of a Brownian bridge.

    ``D = max |S_k| / (sigma_LR sqrt(N))``; the shift is placed where a single mean
    change fits best.  The long-run variance is that of :data:`STEP_BATCHES` batch means
    of the residual less that shift.  A wander slower than a few dozen samples (bias
    instability a level leaves beside it) raises the CUSUM as a step does, and a kernel
    estimate over that many lags does not see it (:func:`mean_stability`, which the level
    answers): a synthetic day of a static accelerometer at 1 Hz with no step read ``D`` 7.0
    (p 2e-43) with Newey-West's bandwidth, 1.9 with batch means.  With the shift taken
    out first, a true step does not inflate the variance it is judged against, which
    would cost the test its power (Vogelsang 1999).

    References
    ----------
    B. Schmeiser, "Batch size effects in the analysis of simulation output", *Operations
    Research* 30(3), 1982.
    T. J. Vogelsang, "Sources of nonmonotonic power when testing for a shift in mean of a
    dynamic time series", *Journal of Econometrics* 88(2), 1999.
    """
    n = len(residual)
    r = residual - residual.mean()
    cusum = np.cumsum(r)
    k = np.arange(1, n)
    split = int(k[np.argmax(np.abs(cusum[:-1]) / np.sqrt(k * (n - k) / n))])
    shift = float(residual[split:].mean() - residual[:split].mean())
    lrv, batches = _batch_variance(np.r_[r[:split] - r[:split].mean(),
                                         r[split:] - r[split:].mean()])
    d = float(np.max(np.abs(cusum)) / math.sqrt(max(lrv, 1e-300) * n))
    rss0 = float(r @ r)
    reduction = cusum[split - 1] ** 2 * n / (split * (n - split))  # of a single mean shift
    bic_gain = n * math.log(rss0 / (rss0 - reduction)) - 2 * math.log(n)  # shift and time
    return Finding("step", d, _bridge_sf(d, batches - 1), alpha,
                   {"time_s": float(time[split]), "shift": shift, "bic_gain": float(bic_gain)},
                   {"time": thinned(time), "cusum": thinned(cusum)})


def _batch_variance(x: np.ndarray) -> tuple[float, int]:
    """Return the long-run variance of the centred ``x`` by batch means, and the batches.

    ``b * sum(m^2) / (B - 1)`` over the means ``m`` of ``B`` = :data:`STEP_BATCHES` batches
    of ``b`` samples (fewer batches, of two samples at least, when ``x`` is short), times
    ``(1 + phi) / (1 - phi)`` for the lag-one correlation ``phi`` of the means: the AR(1)
    prewhitening of Andrews and Monahan (1992) applied to the batches.  A bias instability
    slower than a batch, which a level follows and a step model would freeze, leaves
    neighbouring batch means alike; without the factor its CUSUM passes for a step
    (ADIS16405 gz: a shift at 51 min that the bias undid within the hour read ``D`` 3.8,
    p 9e-8, batch means correlated 0.62).  ``phi`` is taken as 0 within chance of
    independent means (Bartlett's ``1.96 / sqrt(B)``, reached by chance one time in forty
    on 30 batches), where the factor would only cost a short record's step its power, and
    as at most :data:`MAX_BATCH_CORRELATION`.

    References
    ----------
    D. W. K. Andrews and J. C. Monahan, "An improved heteroskedasticity and autocorrelation
    consistent covariance matrix estimator", *Econometrica* 60(4), 1992.
    """
    batches = max(2, min(STEP_BATCHES, len(x) // 2))
    b = len(x) // batches
    means = x[: b * batches].reshape(batches, b).mean(axis=1)
    square = float(means @ means)
    phi = float(means[1:] @ means[:-1]) / square if batches > 2 and square > 0 else 0.0
    if phi <= 1.96 / math.sqrt(batches):  # within chance of independent means: no factor
        phi = 0.0
    phi = min(phi, MAX_BATCH_CORRELATION)
    return b * square / (batches - 1) * (1 + phi) / (1 - phi), batches


def _bridge_sf(d: float, dof: int, nodes: int = 400) -> float:
    """Return ``P(sup |B(t)| > d sqrt(V))``, ``B`` a Brownian bridge, ``V ~ chi2(dof) / dof``.

    The Kolmogorov tail with the long-run variance estimated from ``dof + 1`` batches, as
    Student's t is the normal's with an estimated variance: averaged over ``V``'s quantiles
    at ``nodes`` midpoints.  With 30 batches of white noise, 0.25 % of 400 records fired at
    0.001 and 1.5 % at 0.01; with the Kolmogorov tail alone, 0.75 % and 4.5 %.
    """
    v = stats.chi2.ppf((np.arange(nodes) + 0.5) / nodes, dof) / dof
    return float(np.mean(stats.kstwobign.sf(d * np.sqrt(v))))


def allan(residual: np.ndarray, rate: float, alpha: float = ALPHA) -> Finding:
    """Overlapping Allan deviation (allantools) at the longest tau against white noise.

    Under a white residual ``adev(tau)^2`` is ``adev_white(tau)^2 chi2(edf)/edf``
    (edf from Greenhall's algorithm); the statistic is the ratio at the longest
    tau with at least ten clusters, and the long-tau slope is reported.
    """
    n = len(residual)
    m = np.unique(np.geomspace(1, max(1, n // 10), 40).astype(int))
    taus, adev = allantools.oadev(residual, rate=rate, data_type="freq",
                                  taus=(m + 0.1) / rate)[:2]  # m back, truncated or rounded
    white = adev[0] * np.sqrt(taus[0] / taus)
    ratio2 = float((adev[-1] / white[-1]) ** 2)
    edf = float(allantools.edf_greenhall(alpha=0, d=2, m=int(round(taus[-1] * rate)), N=n,
                                         overlapping=True))
    top = taus >= taus[-1] / 10
    slope = float(np.polyfit(np.log(taus[top]), np.log(adev[top]), 1)[0]) if top.sum() > 1 else 0.0
    return Finding("allan", ratio2, float(stats.chi2.sf(ratio2 * edf, edf)), alpha,
                   {"tau_max_s": float(taus[-1]), "slope": slope, "ratio": math.sqrt(ratio2)},
                   {"taus": taus, "adev": adev, "white": white})
