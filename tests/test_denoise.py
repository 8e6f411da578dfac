import math

import numpy as np
import pytest
from scipy.signal import freqz

from fosmodel import InputError
from fosmodel.noise.denoise import (
    DENOISERS,
    denoise,
    kaiser_lowpass,
    wavelet_band_hz,
    wavelet_lowpass,
)

RATE = 200.0
N = 20_000
T = np.arange(N) / RATE
LOW = np.sin(2 * np.pi * 1.0 * T)      # inside every pass band
HIGH = np.sin(2 * np.pi * 40.0 * T)    # far inside every stop band
MID = slice(N // 4, 3 * N // 4)         # away from the edge transients


def _amplitude(x, f):
    """Least-squares amplitude of the f Hz sinusoid over the middle of the record."""
    t = T[MID]
    basis = np.c_[np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)]
    coef = np.linalg.lstsq(basis, x[MID], rcond=None)[0]
    return float(np.hypot(*coef))


def _db(x):
    return 20 * math.log10(np.max(np.abs(x[MID])))


# -- Kaiser FIR --------------------------------------------------------------------------


def test_kaiser_keeps_1_hz_and_removes_40_hz():
    out = kaiser_lowpass(LOW + HIGH, RATE)
    assert out.shape == (N,)
    # A Kaiser design with A = 100 dB has pass-band ripple delta = 1e-5; filtfilt squares
    # the response, so in the pass band |gain - 1| <= (1 + delta)^2 - 1 (well within 1e-3),
    # and with zero phase that holds sample by sample.
    delta = 10 ** (-100 / 20)
    bound = (1 + delta) ** 2 - 1
    assert abs(_amplitude(out, 1.0) - 1) <= bound
    assert np.max(np.abs(out[MID] - LOW[MID])) <= bound
    assert _db(kaiser_lowpass(HIGH, RATE)) <= -80


def test_kaiser_record_shorter_than_the_filter():
    with pytest.raises(InputError, match=r"500 samples.*643 taps"):
        kaiser_lowpass(np.zeros(500), RATE)
    assert kaiser_lowpass(np.zeros(644), RATE).shape == (644,)


@pytest.mark.parametrize("kwargs, message", [
    (dict(rate=0.0), "rate must be a finite number > 0"),
    (dict(rate=RATE, cutoff_hz=99.5), "must lie inside 0-100 Hz"),
    (dict(rate=RATE, transition_hz=0.0), "positive width"),
    (dict(rate=RATE, attenuation_db=10.0), "attenuation_db must be >= 21"),
])
def test_kaiser_bad_design(kwargs, message):
    with pytest.raises(InputError, match=message):
        kaiser_lowpass(LOW, **kwargs)


# -- wavelet (PyWavelets is an optional extra) ---------------------------------------------


@pytest.fixture
def pywt():
    return pytest.importorskip("pywt")


def _db4_detail_leak(pywt, f, levels):
    """Relative RMS of a sinusoid that db4 puts into the detail coefficients.

    At level j the signal is sampled at rate / 2**(j-1); the orthonormal analysis high pass
    G passes |G(w_j)|/sqrt(2) of it, after the low passes H of the coarser-rate stages.
    By Parseval (orthonormal wavelet) this is the relative RMS of what is removed.
    """
    wav = pywt.Wavelet("db4")
    leak2, through = 0.0, 1.0
    for j in range(1, levels + 1):
        w = 2 * np.pi * f * 2 ** (j - 1) / RATE
        gain_hi = abs(freqz(wav.dec_hi, worN=[w])[1][0]) / math.sqrt(2)
        gain_lo = abs(freqz(wav.dec_lo, worN=[w])[1][0]) / math.sqrt(2)
        leak2 += (through * gain_hi) ** 2
        through *= gain_lo
    return math.sqrt(leak2)


def test_wavelet_keeps_1_hz_and_removes_40_hz(pywt):
    out = wavelet_lowpass(LOW + HIGH, levels=4)
    assert out.shape == (N,)
    # db4 has 4 vanishing moments, so its high pass rises as w^4 from DC: at 1 Hz the
    # details take only ~1.4e-3 (relative RMS) of the sinusoid.  That is the tolerance.
    leak = _db4_detail_leak(pywt, 1.0, 4)
    assert 1e-4 < leak < 3e-3
    low_only = wavelet_lowpass(LOW, levels=4)
    rel_rms = np.sqrt(np.mean((low_only[MID] - LOW[MID]) ** 2) / np.mean(LOW[MID] ** 2))
    assert rel_rms <= 1.05 * leak
    assert abs(_amplitude(out, 1.0) - 1) <= leak
    assert _db(wavelet_lowpass(HIGH, levels=4)) <= -40


@pytest.mark.parametrize("n", [5001, 5002, 5003])
def test_wavelet_output_length_equals_input(pywt, n):
    assert wavelet_lowpass(np.random.default_rng(n).standard_normal(n)).shape == (n,)


@pytest.mark.parametrize("denoiser", ["wavelet", "kaiser"])
def test_read_only_and_strided_input(pywt, denoiser):
    frozen = LOW.copy()
    frozen.flags.writeable = False
    strided = np.repeat(LOW, 2)[::2]
    expected = denoise(LOW, RATE, denoiser)
    np.testing.assert_array_equal(denoise(frozen, RATE, denoiser), expected)
    np.testing.assert_array_equal(denoise(strided, RATE, denoiser), expected)


def test_wavelet_band():
    assert wavelet_band_hz(200, 4) == 6.25
    assert wavelet_band_hz(200, 3) == 12.5
    with pytest.raises(InputError, match="levels must be an integer"):
        wavelet_band_hz(200, 0)


def test_wavelet_errors(pywt):
    with pytest.raises(InputError, match="100 samples, needs at least 112"):
        wavelet_lowpass(np.zeros(100), levels=4)
    with pytest.raises(InputError, match="unknown discrete wavelet 'db99'"):
        wavelet_lowpass(LOW, wavelet="db99")
    with pytest.raises(InputError, match="non-finite"):
        wavelet_lowpass(np.r_[LOW, np.nan])


# -- dispatcher --------------------------------------------------------------------------


def test_denoise_dispatches_with_the_paper_defaults(pywt):
    assert DENOISERS == ("none", "wavelet", "kaiser")
    for method in (None, "none"):
        out = denoise(LOW, RATE, method)
        np.testing.assert_array_equal(out, LOW)
        assert out is not LOW
    np.testing.assert_array_equal(denoise(LOW, RATE, "wavelet"), wavelet_lowpass(LOW, levels=4))
    np.testing.assert_array_equal(denoise(LOW, RATE, "kaiser"), kaiser_lowpass(LOW, RATE, 8.0))


def test_denoise_unknown_method_names_the_valid_ones():
    with pytest.raises(InputError, match="unknown denoiser 'kaisr'.*none, wavelet, kaiser"):
        denoise(LOW, RATE, "kaisr")
    with pytest.raises(InputError, match="needs the sampling rate"):
        denoise(LOW, None, "kaiser")
