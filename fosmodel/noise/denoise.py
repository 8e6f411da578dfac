"""Low-pass denoising of inertial records before the AR baselines are fitted.

Tamazin et al. (2013, section 5) fit the Yule-Walker, covariance and Burg models to wavelet-denoised
data ("wavelet denoising of up to 4 levels of decomposition") while FOS gets the raw record;
Skaloud's Kaiser-window FIR low pass (8 Hz cut-off, 100 dB stop band) is the other common
choice.  :func:`denoise` selects one by name so each method can be run on its own protocol.

References
----------
.. [1] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
.. [2] M. El-Diasty, A. El-Rabbany and S. Pagiatakis, "Stochastic Characteristics of
   Temperature-Dependent MEMS-Based Inertial Sensor Error", Proceedings of the ION
   National Technical Meeting, San Diego, CA, 2007.
"""

from __future__ import annotations

import numpy as np
import pywt
from numpy.typing import ArrayLike
from scipy.signal import filtfilt, firwin, kaiserord

from ..core.exceptions import InputError
from ..core.validation import as_signal, check_int, check_positive, did_you_mean

DENOISERS = ("none", "wavelet", "kaiser")

_WAVELET_MODE = "symmetric"
_MIN_KAISER_DB = 21.0


def wavelet_band_hz(rate: float, levels: int) -> float:
    """Upper edge of the band kept by :func:`wavelet_lowpass`: ``rate / 2**(levels + 1)``.

    The level-L approximation is sampled at ``rate / 2**L`` and so spans 0 to half of that:
    6.25 Hz for 4 levels at 200 Hz, where Tamazin et al. (2013) state 12.5 Hz (the approximation's
    *sampling* rate, or the band of 3 levels).
    """
    return check_positive(rate, "rate") / 2 ** (check_int(levels, "levels", 1) + 1)


def wavelet_lowpass(y: ArrayLike, levels: int = 4, wavelet: str = "db4") -> np.ndarray:
    """Wavelet low pass: keep only the level-``levels`` approximation of a multilevel DWT.

    ``pywt.wavedec`` decomposes ``y``, every detail coefficient is set to zero and
    ``pywt.waverec`` reconstructs; the signal is extended symmetrically at its ends
    (``mode="symmetric"``), which avoids the jump that periodic extension creates between
    the two ends of a drifting sensor record.

    The band kept is nominally 0 to ``rate / 2**(levels + 1)`` (:func:`wavelet_band_hz`):
    6.25 Hz for 4 levels at 200 Hz.  Tamazin et al. (2013) report 12.5 Hz for "4 levels" at 200 Hz,
    which is ``rate / 2**levels``; to keep 0-12.5 Hz at 200 Hz use ``levels=3``.  The edge is
    gradual (db4 has 4 vanishing moments), not a brick wall.

    Parameters
    ----------
    y : array-like of shape (N,)
        Finite samples.
    levels : int
        Decomposition levels L >= 1; N must be at least ``(filter length - 1) * 2**L``
        (112 samples for db4 and 4 levels).
    wavelet : str
        A discrete PyWavelets wavelet name (``pywt.wavelist(kind="discrete")``).

    Returns
    -------
    ndarray of shape (N,)

    Raises
    ------
    InputError
        Unknown wavelet, bad level, or a record too short for that many levels.
    """
    # PyWavelets' Cython kernels reject read-only buffers (e.g. views of a loaded DataFrame)
    arr = np.require(as_signal(y, "y"), requirements=["C", "W"])
    levels = check_int(levels, "levels", 1)
    try:
        wav = pywt.Wavelet(wavelet)
    except (ValueError, TypeError):
        raise InputError(
            f"unknown discrete wavelet {wavelet!r}; see pywt.wavelist(kind='discrete')") from None
    needed = (wav.dec_len - 1) * 2**levels
    if len(arr) < needed:
        raise InputError(
            f"record too short for {levels} level(s) of {wav.name}: {len(arr)} samples, "
            f"needs at least {needed}"
        )
    coeffs = pywt.wavedec(arr, wav, mode=_WAVELET_MODE, level=levels)
    kept = [coeffs[0], *(np.zeros_like(c) for c in coeffs[1:])]
    return pywt.waverec(kept, wav, mode=_WAVELET_MODE)[: len(arr)]


def kaiser_lowpass(
    y: ArrayLike,
    rate: float,
    cutoff_hz: float = 8.0,
    transition_hz: float = 2.0,
    attenuation_db: float = 100.0,
) -> np.ndarray:
    """Zero-phase Kaiser-window FIR low pass (Skaloud's denoiser, seed paper 001).

    ``scipy.signal.kaiserord`` gives the length and Kaiser beta for the attenuation and the
    transition width, ``firwin`` the windowed-sinc taps with their -6 dB point at
    ``cutoff_hz`` (the pass band ends at ``cutoff_hz - transition_hz/2`` and the stop band
    starts at ``cutoff_hz + transition_hz/2``), and ``filtfilt`` applies them forward and
    backward, so there is no delay and the magnitude response is squared.

    A Kaiser window design has equal pass- and stop-band ripples,
    ``delta = 10**(-attenuation_db/20)``: 1e-5 for 100 dB, i.e. a pass-band gain within
    ``1 +/- 1e-5`` (``20 log10((1+delta)/(1-delta))`` = 1.7e-4 dB peak to peak).  Skaloud's
    0.0001 dB pass-band spec alone would need delta = 5.8e-6, about 104.8 dB.  After
    ``filtfilt`` the stop band is attenuated by twice ``attenuation_db`` and the pass-band
    gain lies within ``(1 +/- delta)**2``.

    Parameters
    ----------
    y : array-like of shape (N,)
        Finite samples; N must exceed the number of taps (643 with the defaults at 200 Hz).
    rate : float
        Sampling rate in Hz.
    cutoff_hz : float
        Cut-off (middle of the transition band) in Hz.
    transition_hz : float
        Width of the transition band in Hz.
    attenuation_db : float
        Stop-band attenuation A of the single pass, at least 21 dB (the rectangular window).

    Returns
    -------
    ndarray of shape (N,)

    Raises
    ------
    InputError
        Bad rate or band edges outside ``(0, rate/2)``, attenuation below 21 dB, or a record
        not longer than the filter.
    """
    arr = as_signal(y, "y")
    rate = check_positive(rate, "rate")
    nyquist = rate / 2
    low, high = cutoff_hz - transition_hz / 2, cutoff_hz + transition_hz / 2
    if not (transition_hz > 0 and 0 < low and high < nyquist):
        raise InputError(
            f"the Kaiser band {low:g}-{high:g} Hz (cut-off {cutoff_hz:g} Hz, transition "
            f"{transition_hz:g} Hz) must lie inside 0-{nyquist:g} Hz with a positive width"
        )
    if not attenuation_db >= _MIN_KAISER_DB:
        raise InputError(f"attenuation_db must be >= {_MIN_KAISER_DB:g} dB, got {attenuation_db!r}")
    numtaps, beta = kaiserord(attenuation_db, transition_hz / nyquist)
    if len(arr) <= numtaps:
        raise InputError(
            f"record too short for the Kaiser low pass: {len(arr)} samples, but the "
            f"{cutoff_hz:g} Hz filter at {rate:g} Hz ({transition_hz:g} Hz transition, "
            f"{attenuation_db:g} dB) has {numtaps} taps and needs more than {numtaps}"
        )
    taps = firwin(numtaps, cutoff_hz, window=("kaiser", beta), fs=rate)
    return filtfilt(taps, [1.0], arr, padlen=min(3 * numtaps, len(arr) - 1))


def denoise(y: ArrayLike, rate: float | None, method: str | None) -> np.ndarray:
    """Denoise ``y`` by name, with the defaults of the papers.

    Parameters
    ----------
    y : array-like of shape (N,)
        Finite samples.
    rate : float or None
        Sampling rate in Hz (needed by ``"kaiser"`` only).
    method : {None, "none", "wavelet", "kaiser"}
        ``None``/``"none"``: a copy of ``y``; ``"wavelet"``: :func:`wavelet_lowpass` with 4
        levels of db4 (Tamazin et al. 2013); ``"kaiser"``: :func:`kaiser_lowpass` at 8 Hz, 2 Hz
        transition, 100 dB (Skaloud, seed paper 001).

    Returns
    -------
    ndarray of shape (N,)

    Raises
    ------
    InputError
        Unknown method (the valid names are given), or an error of the chosen denoiser.
    """
    if method is None or method == "none":
        return as_signal(y, "y").copy()
    if method == "wavelet":
        return wavelet_lowpass(y)
    if method == "kaiser":
        if rate is None:
            raise InputError("the kaiser denoiser needs the sampling rate")
        return kaiser_lowpass(y, rate)
    raise InputError(
        f"unknown denoiser {method!r}{did_you_mean(str(method), DENOISERS)}; "
        f"valid: {', '.join(DENOISERS)}"
    )
