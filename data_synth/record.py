"""A synthetic record and the composer that builds one from sources.

:func:`compose` draws every source from its own random stream (keyed by the
seed and the source name, so adding a source never changes the others),
generates auxiliary columns before the sources that read them, sums the
components per column, quantizes the columns asked (after every source has
read its inputs), and assembles the ground truth (see :data:`TRUTH_CONVENTIONS`).
"""

from __future__ import annotations

import math
import zlib
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from data_synth.arrays import ARRAY_SOURCES
from data_synth.base import Source, check_column_name
from data_synth.effects import Quantizer
from data_synth.terms import exact_model, terms_json

#: How to read the truth sidecar; stored in it under ``"conventions"``.
TRUTH_CONVENTIONS = {
    "terms": "fosmodel term grammar: '1', 'y[n-L]', '<column>[n-K]', products joined by '*', "
    "powers '^k'. A source's terms describe that component alone, on its channel: 'y' there is "
    "the component itself, so for an AR, Gauss-Markov, random-walk or nonlinear-AR source the "
    "coefficients are those of the error component before white noise and the other sources "
    "are added. terms is [] for white noise and null for effects without a lag form (functions "
    "of time: see their params).",
    "model": "exact equation of the whole target column, 'y' being the target: target[n] = "
    "sum(coef*term) + e[n] with e white of standard deviation innovation_std, when one exists; "
    "null otherwise (e.g. white noise on top of an AR component, functions of time, "
    "quantization).",
    "declared": "false marks an effect the fit is not told about; the data file never names "
    "any effect either way, auxiliary columns are plain named columns.",
    "quantization": "applied to a column once every source has been generated: a source that "
    "reads a column (a temperature bias) reads the quantity itself, the file holds its "
    "quantized read-out.",
    "constants": "per column, the sum of its components that are one constant over the record "
    "(fixed bias, turn-on bias, gravity and earth rate of a static orientation), with their "
    "names; other components keep their own mean (a temperature polynomial's coefs[0], a "
    "random walk's start).",
    "cross_covariance": "per group of columns drawn together, the per-sample covariance at "
    "equal times of the sum of their correlated stationary components (white noise, "
    "Gauss-Markov; each source's own matrix is its params.covariance, a Gauss-Markov one "
    "decays as phi^|k| with the lag k). Components drawn per column are independent across "
    "columns and not in it; no column enters another's error.",
}


@dataclass
class SynthRecord:
    """A generated record: columns, sampling rate, target column and ground truth.

    Attributes
    ----------
    columns : dict of str to ndarray
        float64 columns in the order they are written, the target first.
    rate : float
        Sampling rate in Hz; sample ``n`` is at ``n/rate`` seconds.
    target : str
        Name of the modelled column.
    truth : dict
        JSON-serialisable ground truth (the ``.truth.json`` sidecar).
    """

    columns: dict[str, np.ndarray]
    rate: float
    target: str
    truth: dict[str, Any]

    @property
    def n_samples(self) -> int:
        """Number of samples per column."""
        return len(self.columns[self.target])

    def time(self) -> np.ndarray:
        """Sample times ``n/rate`` in seconds."""
        return np.arange(self.n_samples) / self.rate

    def to_frame(self, time: bool = True) -> pd.DataFrame:
        """The columns as a DataFrame, with a leading ``time`` column (s) if ``time``."""
        data = {"time": self.time()} if time else {}
        data.update(self.columns)
        return pd.DataFrame(data)


def source_rng(seed: int, label: str) -> np.random.Generator:
    """Generator of one source: ``SeedSequence(seed, spawn_key=(crc32(label),))``."""
    return np.random.default_rng(
        np.random.SeedSequence(seed, spawn_key=(zlib.crc32(label.encode()),))
    )


def sample_count(duration: float, rate: float) -> int:
    """``round(duration*rate)``, checked to be at least 2 samples."""
    if not (math.isfinite(rate) and rate > 0 and math.isfinite(duration) and duration > 0):
        raise ValueError(f"need a positive duration and rate, got {duration!r} s at {rate!r} Hz")
    n = round(duration * rate)
    if n < 2:
        raise ValueError(f"{duration} s at {rate} Hz gives {n} samples; need at least 2")
    return n


def compose(
    sources: Sequence[Source],
    *,
    duration: float,
    rate: float,
    seed: int = 0,
    target: str = "gyro_y",
    units: str = "deg/s",
    column_units: Mapping[str, str] | None = None,
    quantizer: Quantizer | None = None,
    quantizers: Mapping[str, Quantizer] | None = None,
    scenario: str = "custom",
    description: str = "",
    extra_truth: Mapping[str, Any] | None = None,
) -> SynthRecord:
    """Generate a record from additive sources.

    Parameters
    ----------
    sources : sequence of Source
        Components; each adds to ``source.channel`` (default ``target``), array
        sources to their ``channels``.  Names must be unique.
    duration, rate : float
        Length in seconds and sampling rate in Hz (``round(duration*rate)`` samples).
    seed : int
        Non-negative seed; the same seed gives the same record.
    target : str
        The modelled column, written first.
    units : str
        Unit of the target column ("deg/s", "deg/h", "m/s^2").
    column_units : mapping, optional
        Unit of every other column (e.g. ``{"temp_c": "degC"}``).
    quantizer : Quantizer, optional
        Quantization of the target, applied to the sum of its components.
    quantizers : mapping of str to Quantizer, optional
        Quantization of any column by name (the target too, if ``quantizer`` is not
        given), applied after every source has been generated.
    scenario, description : str
        Recorded in the truth.
    extra_truth : mapping, optional
        More entries of the truth (an orientation, a session), under keys of their own.

    Returns
    -------
    SynthRecord
    """
    n = sample_count(duration, rate)
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    check_column_name(target)
    labels = [s.label for s in sources]
    if len(set(labels)) != len(labels):
        dup = sorted(k for k, v in Counter(labels).items() if v > 1)
        raise ValueError(f"source names must be unique; give name= to the repeated {dup}")
    order = [target]
    for s in sources:
        order += [c for c in s.outputs(target) if c not in order]
    for c in order:
        check_column_name(c)
    col_units = {target: units, **dict(column_units or {})}
    missing = [c for c in order if c not in col_units]
    if missing:
        raise ValueError(f"give the units of {missing} in column_units")
    quantized = _quantizers(quantizer, quantizers, target, order)

    values, outs = _generate(sources, n, rate, seed, target, order)
    truth_sources = [_source_truth(s, outs[s.label], rate, target, col_units) for s in sources]
    for column, q in quantized.items():
        raw = values[column]
        values[column] = q.apply(raw)
        truth_sources.append(_quantizer_truth(q, values[column] - raw, column, target,
                                              col_units[column]))
    model = None if target in quantized else _model(sources, outs, rate, target, units)
    columns = _columns_truth(sources, order, target, col_units)
    for column, q in quantized.items():
        columns[column]["lsb"] = q.lsb
    truth = {
        "scenario": scenario,
        "description": description,
        "seed": int(seed),
        "rate_hz": float(rate),
        "duration_s": n / rate,
        "n_samples": n,
        "target": target,
        "units": units,
        "columns": columns,
        "sources": truth_sources,
        "model": model,
    }
    constants = _constants(sources, outs, target)
    if constants:
        truth["constants"] = constants
    cross = _cross_covariance(sources, rate, col_units)
    if cross:
        truth["cross_covariance"] = cross
    truth["conventions"] = dict(TRUTH_CONVENTIONS)
    clash = sorted(set(extra_truth or {}) & set(truth))
    if clash:
        raise ValueError(f"extra_truth may not replace the truth's own entries {clash}")
    truth.update(extra_truth or {})
    return SynthRecord({c: values[c] for c in order}, float(rate), target, truth)


def _quantizers(quantizer, quantizers, target, order) -> dict[str, Quantizer]:
    """The quantizer of each column: ``quantizer`` for the target, ``quantizers`` by name."""
    out = dict(quantizers or {})
    if quantizer is not None:
        if target in out:
            raise ValueError(f"the target {target!r} has a quantizer and an entry in quantizers")
        out = {target: quantizer, **out}
    unknown = sorted(set(out) - set(order))
    if unknown:
        raise ValueError(f"quantizers name columns the record does not have: {unknown}")
    return out


def _generate(sources, n, rate, seed, target, order):
    """Run the sources in dependency order; return column sums and each component."""
    values = {c: np.zeros(n) for c in order}
    writers = Counter(c for s in sources for c in s.outputs(target))
    outs: dict[str, np.ndarray] = {}
    pending = list(sources)
    while pending:
        ready = [s for s in pending if all(writers[c] == 0 for c in s.requires)]
        if not ready:
            raise ValueError(
                "circular inputs: "
                + ", ".join(f"{s.label} needs {list(s.requires)}" for s in pending)
            )
        for s in ready:
            complete = {c: v for c, v in values.items() if writers[c] == 0}
            out = np.asarray(s.generate(n, rate, source_rng(seed, s.label), complete), dtype=float)
            cols = s.outputs(target)
            out2d = out.reshape(n, -1)
            if out2d.shape[1] != len(cols):
                raise ValueError(f"{s.label} returned shape {out.shape} for columns {list(cols)}")
            for j, c in enumerate(cols):
                values[c] += out2d[:, j]
                writers[c] -= 1
            outs[s.label] = out
            pending.remove(s)
    return values, outs


def _source_truth(s, out, rate, target, col_units) -> dict[str, Any]:
    cols = s.outputs(target)
    entry = s.truth(rate, col_units[cols[0]], out)
    if len(cols) == 1:
        entry["channel"] = cols[0]
    else:
        entry["channels"] = list(cols)
    return entry


def _columns_truth(sources, order, target, col_units) -> dict[str, dict[str, Any]]:
    info: dict[str, dict[str, Any]] = {
        "time": {"units": "s", "role": "time", "note": "n/rate_hz; written first when requested"}
    }
    for c in order:
        users = [s for s in sources if c in s.requires]
        role = "target" if c == target else ("input" if users else "auxiliary")
        info[c] = {
            "units": col_units[c],
            "role": role,
            "writers": [s.label for s in sources if c in s.outputs(target)],
        }
        if users:
            info[c]["used_by"] = [s.label for s in users]
            info[c]["declared_use"] = any(s.declared for s in users)
    return info


def _quantizer_truth(quantizer, error, column, target, units) -> dict[str, Any]:
    return {
        "kind": quantizer.kind,
        "name": quantizer.kind if column == target else f"{column}_{quantizer.kind}",
        "declared": True,
        "params": quantizer.params(units),
        "terms": None,
        "innovation_std": None,
        "component_std": float(np.std(error)),
        "channel": column,
    }


def _constants(sources, outs, target) -> dict[str, dict[str, Any]]:
    """Per column, the sum of its constant components and their names."""
    out: dict[str, dict[str, Any]] = {}
    for s in sources:
        if s.constant:
            (column,) = s.outputs(target)
            entry = out.setdefault(column, {"value": 0.0, "sources": []})
            entry["value"] += float(outs[s.label][0])
            entry["sources"].append(s.label)
    return out


def _cross_covariance(sources, rate, col_units) -> list[dict[str, Any]]:
    """Per group of columns, the summed equal-time covariance of its stationary array sources."""
    groups: dict[tuple[str, ...], dict[str, Any]] = {}
    for src in sources:
        if not isinstance(src, ARRAY_SOURCES) or src.covariance(rate) is None:
            continue
        units = {col_units[c] for c in src.channels}
        group = groups.setdefault(src.channels, {
            "channels": list(src.channels),
            "covariance": 0.0,
            "sources": [],
            "units": f"({units.pop()})^2" if len(units) == 1 else "products of the column units",
        })
        group["covariance"] = group["covariance"] + src.covariance(rate)
        group["sources"].append(src.label)
    return [{**g, "covariance": g["covariance"].tolist()} for g in groups.values()]


def _model(sources, outs, rate, target, units) -> dict[str, Any] | None:
    """Exact model of the target column (see :func:`data_synth.terms.exact_model`)."""
    reps = [
        s.representation(rate, outs[s.label]) if s.outputs(target) == (target,) else None
        for s in sources
        if target in s.outputs(target)
    ]
    model = exact_model(reps)
    if model is None:
        return None
    return {
        "terms": terms_json(model.terms),
        "innovation_std": model.innovation_std,
        "units": {"innovation_std": units},
    }
