"""Thermal-calibration sweeps: sessions of one static IMU warming and cooling, known biases.

Each session is a board cold-soaked, warmed through some 40 C, held, and let cool (a
chamber ramp, or a board's own heating), at rest in another orientation each time.  Every
axis's bias follows a known polynomial in the temperature, through a first-order thermal
lag when ``lag_s`` is given (the bias follows the die late), beside a turn-on bias drawn per
session, white noise, bias instability and a rate random walk (the wandering bias), all as
:func:`data_synth.imu.sweep_spec` builds them, and quantized at its coarse LSBs.  The
sessions share the sensor: its polynomials, its lag and its noise levels.

Sizes (design choices): MPU-6050-class temperature coefficients, some tens of mdeg/s and a
few mg over 40 C, one axis each of the gyros and the accelerometers linear, quadratic and
cubic, so that a fit must find each degree.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from data_synth.imu import sweep_spec
from data_synth.record import SynthRecord, compose
from data_synth.scenarios import session_seed

#: The bias polynomials about :data:`T_REF_C`: coefficients of powers 0, 1, 2, 3 of
#: ``T - T_REF_C`` (deg/s or m/s^2 per degC^k).
COEFS: dict[str, tuple[float, ...]] = {
    "gx_dps": (0.0, 0.02, 4e-4),
    "gy_dps": (0.0, -0.015),
    "gz_dps": (0.0, 0.01, -3e-4, 8e-6),
    "ax_mps2": (0.0, 3e-3, 6e-5),
    "ay_mps2": (0.0, -2e-3),
    "az_mps2": (0.0, 4e-3, -8e-5, 2e-6),
}
T_REF_C = 25.0
#: Each session's path as (fraction of the session, degC): a cold start, a ramp up at its own
#: rate, a hold, a cool-down; each covers about the range of the others (a session held out
#: is judged where the others were fitted, not where their polynomials are clipped).
SWEEPS = (
    ((0.0, 0.0), (0.35, 50.0), (0.5, 50.0), (1.0, 15.0)),
    ((0.0, 2.0), (0.45, 48.0), (0.55, 48.0), (1.0, 20.0)),
    ((0.0, 1.0), (0.3, 49.0), (0.45, 49.0), (1.0, 10.0)),
)
#: Each session another axis up, as ``UP/NORTH``.
ORIENTATIONS = ("+z/+x", "+x/+y", "-y/+z")
DURATION_S, RATE_HZ = 7200.0, 1.0


def thermal_sessions(seed: int, *, lag_s: float = 0.0, sessions: int = 3,
                     duration: float = DURATION_S, rate: float = RATE_HZ,
                     coefs: Mapping[str, Sequence[float]] | None = None,
                     sweeps: Sequence[Sequence[Sequence[float]]] = SWEEPS,
                     **options: Any) -> list[SynthRecord]:
    """Return ``sessions`` thermal-calibration sweeps of one IMU (the module docstring).

    Parameters
    ----------
    seed : int
        Non-negative; each session draws with its own seed from it.
    lag_s : float
        The thermal lag (s) between the temperature column and every bias (0: none).
    sessions : int
        How many, each with the next of ``sweeps`` and :data:`ORIENTATIONS` (cycled).
    duration, rate : float
        Seconds and Hz of each session.
    coefs : mapping of column to coefficients, optional
        The bias polynomials about :data:`T_REF_C` (:data:`COEFS` if None).
    sweeps : sequence of knots
        The sessions' temperature paths, ``(fraction, degC)`` each.
    **options
        More of :func:`data_synth.imu.sweep_spec`'s arguments (its LSBs: ``temp_lsb``...).

    Returns
    -------
    list of SynthRecord
        The columns ``gx_dps``..``az_mps2`` and ``temp_c``; each truth holds the session's
        turn-on biases and the shared ``thermal`` truth (``coefs``, ``t_ref_c``, ``lag_s``).
    """
    coefs = dict(COEFS if coefs is None else coefs)
    out = []
    for k in range(sessions):
        spec = sweep_spec(duration, sweep=sweeps[k % len(sweeps)],
                          orientation=ORIENTATIONS[k % len(ORIENTATIONS)], sensitivity=coefs,
                          t_ref_c=T_REF_C, lag_s=lag_s, **options)
        extra = {**spec.pop("extra_truth", {}), "session": {"index": k + 1, "count": sessions},
                 "thermal": {"coefs": {c: list(v) for c, v in coefs.items()},
                             "t_ref_c": T_REF_C, "lag_s": lag_s}}
        out.append(compose(duration=duration, rate=rate, seed=session_seed(seed, k),
                           scenario="thermal_sessions", extra_truth=extra, **spec))
    return out
