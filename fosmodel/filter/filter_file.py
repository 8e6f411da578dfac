"""The filter JSON: an error model as a state-space file a client loads with no fosmodel.

One file holds one shaping filter (:mod:`fosmodel.filter.statespace`) and what a Kalman
filter needs besides its matrices::

    x[n] = Phi x[n-1] + B u[n] + G w[n],     var(w) = Q        ("linear")
    x[n] = f(x[n-1], u[n]) + G w[n]                              ("nonlinear", for an EKF)
    z[n] = H x[n] + D u[n] + mu + v[n],      var(v) = R

with ``x0`` and ``P0`` the state and covariance to start from, ``rate_hz`` the sample rate,
and ``inputs`` the entries of ``u`` in order, each with its ``name``, ``unit`` and
``definition`` (:func:`fosmodel.core.derived.describe`: ``"1"`` is the constant, ``t@s`` the
time from the first sample of the record the model was fitted on).  ``Q`` is the covariance
of the driving noise ``w``; a filter that adds a state covariance each step adds
``G Q G'`` (``GQG`` in the file, for convenience).

A ``"nonlinear"`` file has no ``Phi`` or ``B``; ``terms`` give ``f`` as data: with
``z = [x, u - input_offsets]`` (the state, then the inputs centred), the first entry of
``f`` is ``sum_t coef_t prod_{i in factors_t} z[i]``, entries ``1 .. n_lags - 1`` the state
shifted down by one (``f[i] = x[i-1]``), and each level state ``j`` (``level_gains[j] = a``,
state ``n_lags + j``) ``(1 - a) x[n_lags + j] + a f[0]``.  Its Jacobian follows by the
product rule.  ``schema_version`` is :data:`SCHEMA_VERSION`; a reader refuses another.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..core.candidates import Term
from ..core.derived import describe, is_derived
from ..core.exceptions import InputError
from ..io.output import write_text
from .allan_statespace import initial_covariance
from .statespace import CONSTANT, NonlinearStateSpace, StateSpace

__all__ = ["SCHEMA", "SCHEMA_VERSION", "FilterFile", "filter_dict", "input_description",
           "read_filter_file", "write_filter_file"]

SCHEMA = "fosmodel.filter"
SCHEMA_VERSION = 1
EQUATIONS = {
    "linear": "x[n] = Phi x[n-1] + B u[n] + G w[n], var(w) = Q; "
              "z[n] = H x[n] + D u[n] + mu + v[n], var(v) = R",
    "nonlinear": "x[n] = f(x[n-1], u[n]) + G w[n], var(w) = Q, f from terms (z = [x, u - "
                 "input_offsets]; f[0] = sum coef prod z[factors]; f[i] = x[i-1] for 0 < i < "
                 "n_lags; level j: (1 - a_j) x[n_lags + j] + a_j f[0]); "
                 "z[n] = H x[n] + D u[n] + mu + v[n], var(v) = R",
}


def input_description(name: str, units: Mapping[str, str] | None = None) -> dict[str, str]:
    """Return ``{"name", "unit", "definition"}`` of an input of a shaping filter.

    Parameters
    ----------
    name : str
        ``"1"``, a channel's lag ``"temp_c[n-2]"``, a derived column (or its lag) or a user
        column.
    units : mapping of str to str, optional
        Units of the record's channels.
    """
    units = units or {}
    if name == CONSTANT:
        return {"name": name, "unit": "1",
                "definition": "the constant 1 (the intercept and the centring offsets)"}
    try:
        (channel, lag), = Term.parse(name).factors
    except (InputError, ValueError):
        return {"name": name, "unit": units.get(name, "unknown"),
                "definition": f"the column {name!r} as given"}
    delay = f", {lag} sample(s) earlier" if lag else ""
    if is_derived(channel):
        found = describe(channel, units)
        return {"name": name, "unit": found.unit, "definition": found.definition + delay}
    return {"name": name, "unit": units.get(channel, "unknown"),
            "definition": f"the channel {channel!r} as measured{delay}"}


@dataclass(frozen=True)
class FilterFile:
    """A filter JSON read back: the shaping filter and what a Kalman filter starts from."""

    system: StateSpace | NonlinearStateSpace
    R: np.ndarray
    x0: np.ndarray
    P0: np.ndarray
    inputs: tuple[dict[str, str], ...]
    meta: dict[str, Any] = field(default_factory=dict)


def filter_dict(
    system: StateSpace | NonlinearStateSpace, *, n_samples: int | None = None,
    P0: ArrayLike | None = None, x0: ArrayLike | None = None, R: ArrayLike | None = None,
    units: Mapping[str, str] | None = None, meta: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Return the filter JSON of ``system`` as a dict (see the module docstring).

    Parameters
    ----------
    system : StateSpace or NonlinearStateSpace
        From :func:`~fosmodel.filter.statespace.to_state_space`,
        :func:`~fosmodel.filter.statespace.to_nonlinear_state_space` or
        :func:`~fosmodel.filter.allan_statespace.allan_state_space`; its ``rate`` is needed.
    n_samples : int, optional
        Training samples behind the model's mean: ``P0`` is then
        :func:`~fosmodel.filter.allan_statespace.initial_covariance` (a linear system's).
    P0, x0 : array-like, optional
        The starting covariance (else from ``n_samples``) and state (zeros: the mean).
    R : array-like, optional
        Covariance of the measurement noise ``v`` (zeros by default: the states make up the
        output, its white part among them).
    units : mapping of str to str, optional
        Units of the record's channels, for the inputs' descriptions (and ``"output"``).
    meta : mapping, optional
        What the file says besides (source, column, what it was fitted on).

    Raises
    ------
    InputError
        No rate, no ``P0`` and no ``n_samples`` (or a nonlinear system without ``P0``), or
        matrices of the wrong shape.
    """
    if system.rate is None:
        raise InputError("the filter JSON needs the model's sample rate (rate=...)")
    n, d = system.n_states, system.H.shape[0]
    if P0 is None:
        if n_samples is None or not isinstance(system, StateSpace):
            raise InputError("the filter JSON needs P0, or n_samples for a linear model's "
                             "initial covariance")
        P0 = initial_covariance(system, n_samples)
    p0 = _array(P0, (n, n), "P0")
    start = _array(np.zeros(n) if x0 is None else x0, (n,), "x0")
    r = _array(np.zeros((d, d)) if R is None else R, (d, d), "R")
    body = system.to_dict()
    kind = body.pop("kind")
    body.pop("rate", None)
    out: dict[str, Any] = {
        "schema": SCHEMA, "schema_version": SCHEMA_VERSION, "kind": kind,
        "equations": EQUATIONS[kind], "rate_hz": float(system.rate),
        "dt_s": 1.0 / float(system.rate), **dict(meta or {}),
        "n_states": n, "n_inputs": system.n_inputs,
        "inputs": [input_description(name, units) for name in system.input_names],
        **body, "GQG": system.process_covariance().tolist(), "R": r.tolist(),
        "x0": start.tolist(), "P0": p0.tolist(), "n_lags": system.n_lags,
    }
    if units and "column" in out and out["column"] in units:
        out["output_unit"] = units[out["column"]]
    return out


def write_filter_file(
    path: str | os.PathLike[str], system: StateSpace | NonlinearStateSpace, *,
    n_samples: int | None = None, P0: ArrayLike | None = None, x0: ArrayLike | None = None,
    R: ArrayLike | None = None, units: Mapping[str, str] | None = None,
    meta: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Write the filter JSON of ``system`` to ``path``; return what was written.

    The keywords are those of :func:`filter_dict`.
    """
    data = filter_dict(system, n_samples=n_samples, P0=P0, x0=x0, R=R, units=units, meta=meta)
    write_text(os.fspath(path), json.dumps(data, indent=1, allow_nan=False) + "\n")
    return data


def read_filter_file(path: str | os.PathLike[str]) -> FilterFile:
    """Read a filter JSON written by :func:`write_filter_file`.

    Raises
    ------
    InputError
        Not a filter JSON, another schema version, or a missing or malformed entry (named).
    """
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except (OSError, json.JSONDecodeError) as exc:
        raise InputError(f"{os.fspath(path)}: not a readable filter JSON ({exc})") from None
    where = os.fspath(path)
    if not isinstance(data, dict) or data.get("schema") != SCHEMA:
        raise InputError(f"{where}: not a filter JSON (no \"schema\": \"{SCHEMA}\")")
    if data.get("schema_version") != SCHEMA_VERSION:
        raise InputError(f"{where}: schema_version {data.get('schema_version')!r}; this "
                         f"fosmodel reads {SCHEMA_VERSION}")
    try:
        common: dict[str, Any] = dict(
            G=np.asarray(data["G"], dtype=float), H=np.asarray(data["H"], dtype=float),
            Q=np.asarray(data["Q"], dtype=float), mu=float(data["mu"]),
            state_names=tuple(data["state_names"]), input_names=tuple(data["input_names"]),
            level_gains=np.asarray(data["level_gains"], dtype=float),
            D=np.asarray(data["D"], dtype=float).reshape(len(data["H"]),
                                                          len(data["input_names"])),
            rate=float(data["rate_hz"]), channel_means=dict(data.get("channel_means", {})))
        system: StateSpace | NonlinearStateSpace
        if data["kind"] == "linear":
            system = StateSpace(Phi=np.asarray(data["Phi"], dtype=float),
                                B=np.asarray(data["B"], dtype=float).reshape(
                                    len(data["Phi"]), len(data["input_names"])), **common)
        elif data["kind"] == "nonlinear":
            terms = data["terms"]
            system = NonlinearStateSpace(
                coef=np.array([t["coef"] for t in terms], dtype=float),
                factors=tuple(tuple(int(i) for i in t["factors"]) for t in terms),
                term_names=tuple(t["name"] for t in terms),
                input_offsets=np.asarray(data["input_offsets"], dtype=float), **common)
        else:
            raise InputError(f"{where}: kind {data['kind']!r} is neither linear nor nonlinear")
        n = system.n_states
        out = FilterFile(system, _array(data["R"], system.D.shape[:1] * 2, "R"),
                         _array(data["x0"], (n,), "x0"), _array(data["P0"], (n, n), "P0"),
                         tuple(data["inputs"]),
                         {k: v for k, v in data.items() if k in ("source", "column", "model",
                                                                 "fitted_on", "output_unit")})
    except KeyError as exc:
        raise InputError(f"{where}: the filter JSON has no {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"{where}: a malformed entry ({exc})") from None
    if not math.isclose(out.system.rate or 0.0, 1.0 / float(data["dt_s"]), rel_tol=1e-9):
        raise InputError(f"{where}: rate_hz and dt_s disagree")
    return out


def _array(value: ArrayLike, shape: tuple[int, ...], name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape or not np.isfinite(arr).all():
        raise InputError(f"{name} must be a finite array of shape {shape}, got {arr.shape}")
    return arr
