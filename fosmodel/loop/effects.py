"""The effect catalogue: what each kind of finding adds to the FOS candidate set.

================  ====================================================================
kind              candidates added
================  ====================================================================
``aux``           lags 0..K of the channel, and its square ``sq(channel)`` (a
                  temperature enters a bias as a polynomial); or, in its *fast*
                  form, lags 0..K of the channel minus its own local level
                  (``<channel>_fast<T>s``): a coupling through the channel's
                  changes, free of whatever its slow wander does
``periodic``      ``cos@<f>Hz`` and ``sin@<f>Hz`` at the found frequency
``nonlinear``     the cross-product degree raised to 2 (squares and products of the
                  output lags the test looked at)
``level``         local levels ``level@<tau>s`` of the output (:mod:`fosmodel.core.levels`):
                  the wandering bias as a stochastic level, over a grid of time constants
``drift``         functions of time: ``t@s`` and ``exp(-t/<tau>s)`` (the warm-up found);
                  FOS keeps what the data support
``step``          ``step@<time>s``, 0 before the step and 1 after it
================  ====================================================================

Time functions use the record's time from its first sample; every column is
named so that it can be rebuilt from its name (:mod:`fosmodel.core.derived`).  An
effect is a small frozen description that :class:`CandidateFamily` turns into
FOS candidates for a given record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TypeVar

import numpy as np

from ..core.derived import (
    TIME_NAME,
    channel_token,
    channels_read,
    cosine_name,
    derive,
    exp_name,
    fast_name,
    sine_name,
    square_name,
    step_name,
)
from .diagnose import Finding

KINDS = ("aux", "periodic", "nonlinear", "level", "drift", "step")
_T = TypeVar("_T")
#: Tests whose firing points to a slow error, for which a level is offered.
SLOW_TESTS = ("trend", "step", "allan")


@dataclass(frozen=True)
class Effect:
    """One effect the model lacks, as found (or as declared by the user).

    Only the fields of its ``kind`` are set: ``channel`` and ``max_lag`` (aux, with
    ``form="fast"`` and the level's ``tau_s`` for its fast form), ``freq_hz``
    (periodic), ``taus`` (level: the time constants offered), ``form`` and ``tau_s``
    (drift), ``time_s`` (step).
    """

    kind: str
    channel: str | None = None
    max_lag: int | None = None
    freq_hz: float | None = None
    form: str | None = None
    tau_s: float | None = None
    time_s: float | None = None
    taus: tuple[float, ...] | None = None
    evidence: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        """Check the kind.

        Raises
        ------
        ValueError
            A kind not in :data:`KINDS`.
        """
        if self.kind not in KINDS:
            raise ValueError(f"unknown effect kind {self.kind!r}")

    @property
    def is_slow(self) -> bool:
        """A slow relation: a function of time, or a channel with its slow part (full form)."""
        return self.kind in ("drift", "step") or (self.kind == "aux" and self.form != "fast")

    def same_as(self, other: Effect, freq_tol_hz: float = 0.05) -> bool:
        """Whether ``other`` is the same effect.

        The same kind, channel and form (aux) and frequency within ``freq_tol_hz``
        (periodic).
        """
        if self.kind != other.kind:
            return False
        if self.kind == "aux":
            return self.channel == other.channel and self.form == other.form
        if self.kind == "periodic":
            return abs(_required(self, self.freq_hz, "freq_hz")
                       - _required(other, other.freq_hz, "freq_hz")) < freq_tol_hz
        return True

    @property
    def input_name(self) -> str:
        """The channel an ``aux`` effect's lag candidates read: its channel, or its fast form.

        Raises
        ------
        ValueError
            The effect lacks its channel, or its fast form its ``tau_s``.
        """
        channel = _required(self, self.channel, "channel")
        if self.form == "fast":
            return fast_name(channel, _required(self, self.tau_s, "tau_s"))
        return channel_token(channel)  # the channel itself, named so that any header fits

    def describe(self) -> str:
        """Return a short label: ``aux temp_c (lags 0-3)``, ``periodic 7.3137 Hz``, ..."""
        return {
            "aux": lambda: (f"aux {self.channel}, fast part (lags 0-{self.max_lag})"
                            if self.form == "fast" else
                            f"aux {self.channel} (lags 0-{self.max_lag} and its square)"),
            "periodic": lambda: f"periodic {self.freq_hz:.4f} Hz",
            "nonlinear": lambda: "nonlinear (cross-products of degree 2" + (
                f" of y[n-1]..y[n-{self.max_lag}])" if self.max_lag else ")"),
            "level": lambda: "local level" + (
                f" (tau {self.taus[0]:.3g}-{self.taus[-1]:.3g} s)" if self.taus else ""),
            "drift": lambda: f"drift (trend and warm-up, tau {self.tau_s:.3g} s)",
            "step": lambda: f"step at {self.time_s:.4g} s",
        }[self.kind]()


@dataclass(frozen=True)
class CandidateFamily:
    """What the FOS model of the loop may choose from: lags, degree, channels and columns.

    ``columns`` maps user-column names to their values over the whole record,
    ``inputs`` the input channels (``exog_lags``) to theirs; ``levels`` are the
    time constants (s) of the level candidates.
    """

    max_lag: int
    degree: int = 1
    exog_lags: Mapping[str, int] = field(default_factory=dict)
    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    levels: tuple[float, ...] = ()
    inputs: Mapping[str, np.ndarray] = field(default_factory=dict)
    product_lags: int | None = None

    def add(self, effect: Effect, channels: Mapping[str, np.ndarray], n_samples: int,
            rate: float, train: slice) -> CandidateFamily:
        """Return this family with the candidates of ``effect`` added.

        For a record of ``n_samples`` at ``rate`` Hz whose fitting segment is ``train`` (the
        training mean of a squared channel).

        Raises
        ------
        ValueError
            ``effect`` lacks a field its kind needs.
        """
        exog, degree, levels = dict(self.exog_lags), self.degree, self.levels
        product_lags = self.product_lags
        names: list[str] = []
        if effect.kind == "aux":
            name, max_lag = effect.input_name, _required(effect, effect.max_lag, "max_lag")
            exog[name] = max(exog.get(name, 0), max_lag)
            if name not in channels:  # a fast part, or a header spelled out as a token
                channels = {**channels, name: derive(name, n_samples, rate, channels, {})}
            if effect.form != "fast":
                names.append(square_name(_required(effect, effect.channel, "channel")))
        elif effect.kind == "periodic":
            freq_hz = _required(effect, effect.freq_hz, "freq_hz")
            names += [cosine_name(freq_hz), sine_name(freq_hz)]
        elif effect.kind == "nonlinear":
            degree = max(degree, 2)
            product_lags = effect.max_lag
        elif effect.kind == "level":
            levels = tuple(sorted({*levels, *_required(effect, effect.taus, "taus")}))
        elif effect.kind == "drift":
            names += [TIME_NAME, exp_name(_required(effect, effect.tau_s, "tau_s"))]
        else:  # step
            names.append(step_name(_required(effect, effect.time_s, "time_s")))
        means = {ch: float(channels[ch][train].mean()) for ch in channels_read(names)}
        cols = {**self.columns,
                **{name: derive(name, n_samples, rate, channels, means) for name in names}}
        inputs = {**self.inputs, **{ch: channels[ch] for ch in exog if ch not in self.inputs}}
        return replace(self, degree=degree, exog_lags=exog, columns=cols, levels=levels,
                       inputs=inputs, product_lags=product_lags)


def _required(effect: Effect, value: _T | None, name: str) -> _T:
    """Return ``value``, the field ``name`` of ``effect``.

    Raises
    ------
    ValueError
        ``value`` is None: the effect lacks a field its kind needs.
    """
    if value is None:
        raise ValueError(f"a {effect.kind} effect needs its {name}")
    return value


def effects_from(findings: list[Finding], aux_max_lag: int,
                 level_taus: tuple[float, ...] = (), fast_tau_s: float | None = None,
                 ) -> list[Effect]:
    """Return the candidate effects that the fired findings point to.

    A slow residual usually fires the trend, the step and the Allan test at
    once.  A wandering bias is offered as a local level (over ``level_taus``)
    whenever one of them fires, beside the deterministic drift and step; how
    each extrapolates out of sample chooses.  A channel is offered as it is
    and, with ``fast_tau_s``, in its fast form (minus its local level over
    ``fast_tau_s``).
    """
    out = []
    slow = [f for f in findings if f.fired and f.test in SLOW_TESTS]
    if slow and level_taus:
        strongest = min(slow, key=lambda f: f.p_value)
        out.append(Effect("level", taus=tuple(level_taus), evidence={
            **strongest.to_dict(), "slow_tests": [f.test for f in slow]}))
    for f in (f for f in findings if f.fired):
        if f.test == "aux":
            lags = max(aux_max_lag, f.evidence["lag"])
            out.append(Effect("aux", channel=f.evidence["channel"], max_lag=lags,
                              evidence=f.to_dict()))
            if fast_tau_s is not None:
                out.append(Effect("aux", channel=f.evidence["channel"], max_lag=lags,
                                  form="fast", tau_s=fast_tau_s, evidence=f.to_dict()))
        elif f.test == "periodic":
            out.append(Effect("periodic", freq_hz=f.evidence["freq_hz"], evidence=f.to_dict()))
        elif f.test == "nonlinear":
            out.append(Effect("nonlinear", max_lag=f.evidence["max_lag"], evidence=f.to_dict()))
        elif f.test == "step":
            out.append(Effect("step", time_s=f.evidence["time_s"], evidence=f.to_dict()))
        elif f.test == "trend":
            out.append(Effect("drift", form=f.evidence["form"], tau_s=f.evidence["tau_s"],
                              evidence=f.to_dict()))
    return out
