"""The noise parameters of a whole IMU: every axis's Allan fit, and the files filters read.

:func:`imu_noise` runs :func:`fosmodel.noise.allan.allan_deviation` and
:func:`fosmodel.noise.allan_fit.fit_noise` on each column of a record (three gyros and
three accelerometers, say); :class:`ImuNoise` sets the axes side by side in
one table and one figure per sensor type, and writes them in SI in the forms
people paste into a filter or a VIO configuration:

- Kalibr's ``imu.yaml`` (:meth:`ImuNoise.kalibr_yaml`):
  ``gyroscope_noise_density`` (rad/s/sqrt(Hz)) and
  ``accelerometer_noise_density`` (m/s^2/sqrt(Hz)) are the white-noise
  coefficient N; ``gyroscope_random_walk`` (rad/s^2/sqrt(Hz)) and
  ``accelerometer_random_walk`` (m/s^3/sqrt(Hz)) the rate random walk K.  In
  Allan terms, N (units*sqrt(s)) *is* the continuous-time noise density
  (units/sqrt(Hz)), and K (units/sqrt(s)) the density of the bias's
  driving noise (units/s/sqrt(Hz)); only the units change, by the factor
  from the record's units to rad/s or m/s^2.
- MATLAB's ``imuSensor`` parameters (:meth:`ImuNoise.matlab_script`):
  ``NoiseDensity`` = N, ``BiasInstability`` = B (the IEEE Std 952
  coefficient, as MathWorks' Allan variance example reads it: the floor
  divided by 0.664), ``RandomWalk`` = K, per axis.
- A plain JSON of the same per axis (:meth:`ImuNoise.to_dict`).
- OpenVINS, VINS-Mono/VINS-Fusion, ORB-SLAM3, PX4 EKF2 and ArduPilot EKF3, each converted
  as its own code discretises the noise (:mod:`fosmodel.noise.exports`).

Every export may be inflated for a moving platform (``inflate``), and says by how much.

A one-number field (Kalibr has one value per sensor) takes the *largest*
value over the sensor's axes: a filter tuned below an axis's noise
trusts that axis too much.  A term the fit does not resolve is exported as
its upper limit, never as 0 (Kalibr refuses a zero random walk, and zero
would claim a bias that never moves); the files say which values are limits.

Each axis's sensor and units are given per column (``gx=deg/s``, whose units
tell the sensor), declared by its file or read from its name (``gx_dps``): see
:mod:`fosmodel.noise.axes`.

References
----------
IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test
Procedure for Single-Axis Interferometric Fiber Optic Gyros*, Annex C.
J. Rehder, J. Nikolic, T. Schneider, T. Hinzmann and R. Siegwart,
"Extending kalibr: calibrating the extrinsics of multiple IMUs and of
individual axes", ICRA 2016; Kalibr wiki, "IMU Noise Model".
MathWorks, "Inertial Sensor Noise Analysis Using Allan Variance" and the
``gyroparams``/``accelparams`` reference pages.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .._version import __version__
from ..core.exceptions import InputError
from ..io.figures import wrap_title
from ..io.output import path_name, save_figure, write_tables, write_text
from ..typeset.latex import mathtext_units
from ..typeset.summary import Summary
from .allan import FLICKER_FLOOR, AllanResult, allan_deviation
from .allan_fit import GAUSS_MARKOV, NoiseFit, fit_noise
from .allan_report import BEYOND, frame_ratio, plot_ratio, write_allan
from .axes import SENSORS, Axis
from .checks import GRAVITY_TOLERANCE
from .exports import (
    GM_WHITE_MAX_TC_S,
    Density,
    NoiseExport,
    clamp_notes,
    export_files,
    exports_dict,
    kalibr_yaml,
)
from .metrics import STANDARD_GRAVITY, to_si_scale

#: Exported terms: white noise, bias instability, rate random walk.
EXPORTED = ("N", "B", "K")
_SI_UNITS = {
    "gyro": {"N": "rad/s/sqrt(Hz)", "B": "rad/s", "K": "rad/s^2/sqrt(Hz)"},
    "accel": {"N": "m/s^2/sqrt(Hz)", "B": "m/s^2", "K": "m/s^3/sqrt(Hz)"},
}


@dataclass(frozen=True)
class AxisNoise:
    """One axis: its column, sensor and units, its Allan deviation and its fit."""

    axis: Axis
    result: AllanResult
    fit: NoiseFit

    def value(self, term: str) -> tuple[float, str]:
        """Return a term's coefficient in the record's units and what it is.

        That is ``"fitted"``, ``"upper limit"`` (not resolved) or ``"not fitted"`` (NaN).
        """
        if term not in self.fit.terms:
            return math.nan, "not fitted"
        return self.fit.conservative(term)

    def si(self, term: str) -> float:
        """Return a term's exported value (:meth:`value`) in SI: rad/s or m/s^2 based."""
        return self.value(term)[0] * to_si_scale(self.axis.sensor, self.axis.units)

    def gm_white_si(self) -> float:
        """Return the white-like part of a short Gauss-Markov term in SI, 0 if there is none.

        A first-order Gauss-Markov term of standard deviation ``G`` and correlation time ``Tc``
        has the rate spectrum ``2 G^2 Tc / (1 + (2 pi f Tc)^2)``: white at ``2 G^2 Tc`` below
        ``1/(2 pi Tc)``, and its Allan variance tends to ``2 G^2 Tc / tau`` beyond ``Tc``, as
        white noise of density ``G sqrt(2 Tc)`` would.  Where ``Tc`` is at most
        :data:`~fosmodel.noise.exports.GM_WHITE_MAX_TC_S`, a filter with no state for it sees
        that much more white noise than ``N``.
        """
        tc = self.fit.gm_tc
        if GAUSS_MARKOV not in self.fit.terms or tc is None or tc > GM_WHITE_MAX_TC_S:
            return 0.0
        return (self.fit.coefficients[GAUSS_MARKOV] * math.sqrt(2.0 * tc)
                * to_si_scale(self.axis.sensor, self.axis.units))

    def filter_white_si(self) -> float:
        """Return the white noise a filter needs in SI: ``sqrt(N^2 + 2 G^2 Tc)``.

        ``G sqrt(2 Tc)`` is :meth:`gm_white_si`, 0 without a short Gauss-Markov term.
        """
        return math.hypot(self.si("N"), self.gm_white_si())


@dataclass(frozen=True)
class ImuNoise:
    """The Allan noise parameters of several axes of one record."""

    axes: tuple[AxisNoise, ...]
    rate: float
    source: str
    gravity: float | None = None

    def of(self, sensor: str) -> list[AxisNoise]:
        """Return the axes of one sensor type, in the order given."""
        return [a for a in self.axes if a.axis.sensor == sensor]

    def worst(self, sensor: str, term: str) -> tuple[float, AxisNoise] | None:
        """Return the largest SI value of a term over a sensor's axes, and its axis (or None)."""
        axes = [a for a in self.of(sensor) if math.isfinite(a.si(term))]
        if not axes:
            return None
        top = max(axes, key=lambda a: a.si(term))
        return top.si(term), top

    def export(self, inflate: float = 1.0) -> NoiseExport:
        """Gather the per-sensor values every VIO and autopilot export takes, times ``inflate``.

        Per sensor the largest ``N`` and ``K`` over its axes (:meth:`worst`), in SI
        (:mod:`fosmodel.noise.exports`).

        Raises
        ------
        InputError
            No gyro or no accelerometer axis, a sensor whose ``N`` or ``K`` no axis has, or an
            ``inflate`` below 1 or not finite.
        """
        if not (math.isfinite(inflate) and inflate >= 1.0):
            raise InputError(f"the inflation factor must be at least 1 (a moving platform is "
                             f"noisier than a static one), got {inflate:g}")
        missing = [s for s in SENSORS if not self.of(s)]
        if missing:
            raise InputError(f"each VIO and autopilot export needs gyro and accelerometer axes; "
                             f"there is no {' and no '.join(missing)} column")
        densities: dict[tuple[str, str], Density] = {}
        for sensor in SENSORS:
            for term in ("N", "K"):
                if self.worst(sensor, term) is None:
                    raise InputError(f"the exports need the {sensor} {_TERM_NAMES[term]} "
                                     f"(Allan {term}); no {sensor} axis has it fitted")
                if term == "N":  # with a short Gauss-Markov term's white-like part
                    axes = [a for a in self.of(sensor) if math.isfinite(a.filter_white_si())]
                    top = max(axes, key=lambda a: a.filter_white_si())
                    densities[sensor, term] = Density(
                        top.filter_white_si(), top.axis.column, top.value(term)[1],
                        top.gm_white_si(), top.fit.gm_tc if top.gm_white_si() > 0 else None)
                else:
                    value, axis = self.worst(sensor, term)  # type: ignore[misc]
                    densities[sensor, term] = Density(value, axis.axis.column,
                                                      axis.value(term)[1])
        gravity, told = ((self.gravity, "the record's mean specific force at rest")
                         if self.gravity is not None else (STANDARD_GRAVITY, "standard gravity"))
        return NoiseExport(densities, self.rate, Path(self.source).name,
                           tuple(a.axis.column for a in self.axes), float(inflate),
                           gravity, told)

    def fit_warnings(self) -> list[str]:
        """Say, one sentence per axis, where the Allan fit misses the measured deviation.

        Beyond the deviation's 95 % interval and by more than the allowed factor
        (:meth:`fosmodel.noise.allan_fit.NoiseFit.misses`); empty when every fit holds.
        """
        out = []
        for a in self.axes:
            misses = a.fit.misses()
            if misses:
                tau, ratio = misses[0]
                out.append(f"{a.axis.column}: the IEEE Std 952 fit misses the measured Allan "
                           f"deviation beyond its 95 % interval at {len(misses)} averaging "
                           f"time(s) (fit/data {ratio:.2f} at tau = {tau:.3g} s first); see "
                           "its figure's lower panel")
        return out

    def export_notes(self, inflate: float = 1.0) -> list[str]:
        """Say what the console should about the exports: each value clamped to its range.

        Empty without gyro and accelerometer axes (there are no exports then).
        """
        if not all(self.of(s) for s in SENSORS):
            return []
        return clamp_notes(self.export(inflate))

    def table(self) -> pd.DataFrame:
        """Tabulate N, B, K of each axis beside the classic read-offs, in navigation units.

        A limit reads "< value"; beside them the datasheet's in-run bias stability, and how
        the fit follows the curve.
        """
        return pd.DataFrame([_row(a) for a in self.axes])

    def si_table(self) -> pd.DataFrame:
        """One row per axis: the exported values in SI and whether each is a limit."""
        rows = []
        for a in self.axes:
            row: dict[str, object] = {"Column": a.axis.column, "Sensor": a.axis.sensor}
            for term in EXPORTED:
                row[f"{term} ({_SI_UNITS[a.axis.sensor][term]})"] = a.si(term)
                row[f"{term} is"] = a.value(term)[1]
            rows.append(row)
        return pd.DataFrame(rows)

    def summary(self) -> Summary:
        """Summarise the record's facts and how each column's sensor and units were told."""
        info = [("Source", Path(self.source).name), ("Rate", f"{self.rate:g} Hz"),
                ("Axes", f"{len(self.axes)}"),
                ("Samples", f"{self.axes[0].result.n_samples}")]
        notes = [f"Columns: {'; '.join(a.axis.describe() for a in self.axes)}.",
                 "N at tau = 1 s on the -1/2 line, K at 3 s on the +1/2 line, B = minimum / "
                 "0.664 (read-offs); in-run bias stability = the minimum of the deviation "
                 "(datasheet convention). '<' marks an upper limit (term not resolved)."]
        notes += [f"WARNING: {line}." for line in self.fit_warnings()]
        return Summary("Allan noise parameters per axis (IEEE Std 952)", info, self.table(),
                       notes)

    def to_dict(self, inflate: float = 1.0) -> dict[str, Any]:
        """Return the exported values as a JSON-ready dict: per axis and per sensor.

        Per axis the values in SI (with their units and whether each is a limit) and the full
        fit; per sensor the one-number values (largest axis), as measured; with gyro and
        accelerometer axes, every export's parameters after ``inflate``
        (:func:`fosmodel.noise.exports.exports_dict`).
        """
        axes = []
        for a in self.axes:
            terms = {}
            for term in EXPORTED:
                value, kind = a.value(term)
                terms[term] = {"value": _finite(a.si(term)),
                               "units": _SI_UNITS[a.axis.sensor][term], "is": kind,
                               "record_units_value": _finite(value)}
            axes.append({"column": a.axis.column, "sensor": a.axis.sensor,
                         "units": a.axis.units, "told": a.axis.told,
                         "noise_density": terms["N"], "bias_instability": terms["B"],
                         "random_walk": terms["K"],
                         "allan": {"taus_s": a.result.taus.tolist(),
                                   "adev": a.result.adev.tolist()},
                         "fit": a.fit.to_dict()})
        out = {"source": self.source, "rate_hz": self.rate, "tool": f"fosmodel {__version__}",
               "axes": axes, "one_number": self._one_number()}
        if all(self.of(s) for s in SENSORS):
            out["exports"] = exports_dict(self.export(inflate))
        return out

    def _one_number(self) -> dict[str, Any]:
        out = {}
        for sensor in SENSORS:
            for term, field in (("N", "noise_density"), ("K", "random_walk")):
                top = self.worst(sensor, term)
                if top is not None:
                    value, axis = top
                    out[f"{_KALIBR_NAME[sensor]}_{field}"] = {
                        "value": value, "units": _SI_UNITS[sensor][term],
                        "axis": axis.axis.column, "is": axis.value(term)[1]}
        return out

    def kalibr_yaml(self, rostopic: str = "/imu0", inflate: float = 1.0) -> str:
        """Kalibr's ``imu.yaml``: per sensor the largest N and K over its axes, in SI.

        Times ``inflate`` (:func:`fosmodel.noise.exports.kalibr_yaml`).

        Raises
        ------
        InputError
            The record has no gyro or no accelerometer axis (Kalibr needs both).
        """
        return kalibr_yaml(self.export(inflate), rostopic)

    def matlab_script(self, inflate: float = 1.0) -> str:
        """MATLAB ``gyroparams``/``accelparams`` (per axis, SI, times ``inflate``), imuSensor."""
        lines = [f"% IMU noise from the Allan deviation of {Path(self.source).name} by fosmodel "
                 f"{__version__}.",
                 (f"% Inflated {inflate:g}x for a moving platform: every value is "
                  f"{inflate:g} times the static record's." if inflate != 1.0 else
                  "% Not inflated: the static record's values."),
                 "% NoiseDensity = N, BiasInstability = B (the IEEE Std 952 flicker coefficient, "
                 "Allan floor 0.664 B), RandomWalk = K;",
                 "% one value per axis in the order given, or the largest over the axes when a "
                 "sensor has not exactly three. Upper limits (terms not resolved) are marked.",
                 "% A bounded bias (Gauss-Markov) has no parameter of its own here; the datasheet "
                 "convention's bias instability, the fitted curve's minimum / 0.664, is given "
                 "beside each sensor."]
        made = []
        for sensor, maker in (("gyro", "gyroparams"), ("accel", "accelparams")):
            axes = self.of(sensor)
            if not axes:
                continue
            lines.append(f"% {sensor}: {', '.join(a.axis.column for a in axes)}")
            sheet = [inflate * a.fit.bias_stability()[0] / FLICKER_FLOOR
                     * to_si_scale(sensor, a.axis.units) for a in axes]
            lines.append("%   datasheet bias instability (fit minimum / 0.664): "
                         + " ".join(f"{v:.6e}" if math.isfinite(v) else "none (no minimum)"
                                    for v in sheet))
            pairs = []
            for term, prop in (("N", "NoiseDensity"), ("B", "BiasInstability"),
                               ("K", "RandomWalk")):
                limits = [a.axis.column for a in axes if a.value(term)[1] != "fitted"]
                if limits:
                    lines.append(f"%   {prop}: upper limit on {', '.join(limits)}")
                pairs.append(f"'{prop}', {_matlab_values(axes, term, inflate)}")
            lines.append(f"{sensor} = {maker}(" + ", ...\n    ".join(pairs) + ");")
            made.append(sensor)
        if len(made) == 2:  # imuSensor has no gyro-only or accelerometer-only type
            lines.append(f"imu = imuSensor('accel-gyro', 'SampleRate', {self.rate:.6g}, "
                         "'Gyroscope', gyro, 'Accelerometer', accel);")
        return "\n".join(lines) + "\n"

    def figures(self) -> dict[str, Figure]:
        """Plot one figure per sensor type: each axis's deviation, band and fit; fit/data below."""
        return {sensor: _sensor_figure(self.of(sensor), sensor) for sensor in SENSORS
                if self.of(sensor)}


_KALIBR_NAME = {"gyro": "gyroscope", "accel": "accelerometer"}
_TERM_NAMES = {"N": "white noise", "K": "bias random walk"}


def _axes_text(axes: Sequence[AxisNoise]) -> str:
    return ", ".join(a.axis.column for a in axes)


def _matlab_values(axes: Sequence[AxisNoise], term: str, inflate: float) -> str:
    values = [inflate * a.si(term) for a in axes]
    if len(values) != 3:
        values = [max(values)]
    text = " ".join(f"{v:.6e}" for v in values)
    return f"[{text}]" if len(values) > 1 else text


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _row(a: AxisNoise) -> dict[str, Any]:
    fit = a.fit
    ratio = fit.model_adev(fit.fitted_taus) / a.result.adev[fit.start:]
    return {"Column": a.axis.column, "Sensor": a.axis.sensor, **fit.conventions(),
            "fit/data min (fitted taus)": float(ratio.min()), "max": float(ratio.max()),
            "misses": len(fit.misses())}


def _sensor_figure(axes: Sequence[AxisNoise], sensor: str) -> Figure:
    """Every axis of one sensor in the first axis's units."""
    units = axes[0].axis.units
    fig = Figure(figsize=(7.5, 6.6), layout="constrained")
    top, low = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    beyond = False
    for i, a in enumerate(axes):
        res, fit, color = a.result, a.fit, f"C{i}"
        scale = to_si_scale(sensor, a.axis.units) / to_si_scale(sensor, units)
        top.fill_between(res.taus, scale * res.lower, scale * res.upper, color=color, alpha=0.15)
        top.loglog(res.taus[fit.start:], scale * res.adev[fit.start:], "o", color=color, ms=3,
                   label=a.axis.column)
        top.loglog(res.taus[:fit.start], scale * res.adev[:fit.start], "o", color=color,
                   mfc="none", ms=3)
        grid = np.geomspace(res.taus[0], res.taus[-1], 300)
        top.loglog(grid, scale * fit.model_adev(grid), "-", color=color, lw=1.0)
        beyond |= plot_ratio(low, res.taus, fit.model_adev(res.taus) / res.adev, fit.start,
                             color)
    if any(a.fit.start for a in axes):  # one entry for every axis's hollow dots
        top.plot([], [], "o", color="0.3", mfc="none", ms=3,
                 label="left out of the fit (the sensor's filtering)")
    top.set_ylabel(f"Allan deviation ({mathtext_units(units)})")
    top.grid(True, which="both", alpha=0.3)
    top.legend(fontsize="small")
    low.axhline(1.0, color="0.4", lw=0.8)
    low.set_xlabel(r"averaging time $\tau$ (s)")
    low.set_ylabel("fit / data")
    low.grid(True, which="both", alpha=0.3)
    if beyond:  # one entry for every axis's triangles
        low.plot([], [], "^", color="0.3", ms=5, label=BEYOND)
        low.legend(fontsize="small")
        frame_ratio(low)
    wrap_title(top, f"{sensor}: overlapping Allan deviation (dots, 68 % bands) and the fitted "
               "IEEE Std 952 sums (lines)", fontsize="medium")
    return fig


def imu_noise(columns: Mapping[str, np.ndarray], axes: Sequence[Axis], rate: float,
              source: str = "", *, min_tau: float | None = None) -> ImuNoise:
    """Fit the IEEE Std 952 terms to the Allan deviation of every axis.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The rate signals by column name (each axis's ``column`` must be in it).
    axes : sequence of Axis
        The columns with their sensors and units (:func:`fosmodel.noise.axes.resolve_axes`).
    rate : float
        Sample rate in Hz.
    source : str
        Where the record came from (named in the exported files).
    min_tau : float, optional
        Shortest averaging time fitted on every axis (default: found per axis).

    Returns
    -------
    ImuNoise
    """
    fitted = []
    for axis in axes:
        result = allan_deviation(columns[axis.column], rate, units=axis.units,
                                 sensor=axis.sensor)
        fitted.append(AxisNoise(axis, result, fit_noise(result, min_tau=min_tau)))
    return ImuNoise(tuple(fitted), float(rate), source, _gravity(columns, axes))


def _gravity(columns: Mapping[str, np.ndarray], axes: Sequence[Axis]) -> float | None:
    """Return the magnitude of the accelerometer triad's mean in m/s^2 if it reads gravity.

    None without three accelerometer axes, or when the mean is not within
    :data:`~fosmodel.noise.checks.GRAVITY_TOLERANCE` of 1 g (gravity removed, or not at rest).
    """
    accels = [a for a in axes if a.sensor == "accel"]
    if len(accels) != 3:
        return None
    mean = [float(np.mean(columns[a.column])) * to_si_scale("accel", a.units) for a in accels]
    g = math.hypot(*mean)
    return g if abs(g / STANDARD_GRAVITY - 1.0) <= GRAVITY_TOLERANCE else None


def write_imu_noise(noise: ImuNoise, out_dir: Path, title: str,
                    inflate: float = 1.0) -> list[Path]:
    """Write the report of several axes in ``out_dir``.

    ``noise.md/csv/tex`` (the table), ``noise_si.md/csv/tex`` (the SI values, before
    ``inflate``), ``allan_gyro.png/svg`` and ``allan_accel.png/svg``, ``imu_noise.json``,
    ``imu_params.m`` (MATLAB), each axis's own report in ``axes/<column>/`` and, when there are
    gyro and accelerometer axes, the files of :data:`fosmodel.noise.exports.FILES` (Kalibr,
    OpenVINS, VINS, ORB-SLAM3, PX4, ArduPilot).  The MATLAB file and the exports are times
    ``inflate``, which each records.
    """
    files = {"imu_noise.json": _json(noise, inflate), "imu_params.m": noise.matlab_script(inflate)}
    if all(noise.of(s) for s in SENSORS):
        files.update(export_files(noise.export(inflate)))
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = write_tables(noise.table(), out_dir, "noise",
                         f"{title}: IEEE Std 952 noise terms of every axis", report=title)
    paths += write_tables(noise.si_table(), out_dir, "noise_si",
                          f"{title}: the noise terms in SI units, before any inflation",
                          report=title)
    for sensor, fig in noise.figures().items():
        fig.suptitle(title)
        paths += save_figure(fig, out_dir, f"allan_{sensor}")
    for a in noise.axes:
        paths += write_allan(a.result, a.fit, out_dir / "axes" / path_name(a.axis.column),
                             f"{title}: {a.axis.column}")
    for name, text in files.items():
        write_text(out_dir / name, text)
        paths.append(out_dir / name)
    return paths


def _json(noise: ImuNoise, inflate: float = 1.0) -> str:
    return json.dumps(noise.to_dict(inflate), indent=1) + "\n"
