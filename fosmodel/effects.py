"""The effect catalogue: what each kind of finding adds to the FOS candidate set.

================  ====================================================================
kind              candidates added
================  ====================================================================
``aux``           lags 0..K of the channel, and its square ``sq(channel)`` (a
                  temperature enters a bias as a polynomial)
``periodic``      ``cos@<f>Hz`` and ``sin@<f>Hz`` at the found frequency
``nonlinear``     the cross-product degree raised to 2 (squares and products of lags)
``drift``         functions of time: ``t`` and ``exp(-t/<tau>s)`` (the warm-up found);
                  FOS keeps what the data support
``step``          ``step@<time>s``, 0 before the step and 1 after it
================  ====================================================================

Time functions use the record's time from its first sample; an effect is a
small frozen description that :class:`CandidateFamily` turns into FOS
candidates for a given record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .diagnose import Finding, trend_columns

KINDS = ("aux", "periodic", "nonlinear", "drift", "step")


@dataclass(frozen=True)
class Effect:
    """One effect the model lacks, as found (or as declared by the user).

    Only the fields of its ``kind`` are set: ``channel`` and ``max_lag`` (aux),
    ``freq_hz`` (periodic), ``form`` and ``tau_s`` (drift), ``time_s`` (step).
    """

    kind: str
    channel: str | None = None
    max_lag: int | None = None
    freq_hz: float | None = None
    form: str | None = None
    tau_s: float | None = None
    time_s: float | None = None
    evidence: dict = field(default_factory=dict, compare=False, hash=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown effect kind {self.kind!r}")

    def same_as(self, other: Effect, freq_tol_hz: float = 0.05) -> bool:
        """The same effect: kind, channel (aux) and frequency within ``freq_tol_hz`` (periodic)."""
        if self.kind != other.kind:
            return False
        if self.kind == "aux":
            return self.channel == other.channel
        if self.kind == "periodic":
            return abs(self.freq_hz - other.freq_hz) < freq_tol_hz
        return True

    def describe(self) -> str:
        """A short label: ``aux temp_c (lags 0-3)``, ``periodic 7.3137 Hz``, ..."""
        return {
            "aux": lambda: f"aux {self.channel} (lags 0-{self.max_lag} and its square)",
            "periodic": lambda: f"periodic {self.freq_hz:.4f} Hz",
            "nonlinear": lambda: "nonlinear (cross-products of degree 2)",
            "drift": lambda: f"drift (trend and warm-up, tau {self.tau_s:.3g} s)",
            "step": lambda: f"step at {self.time_s:.4g} s",
        }[self.kind]()


@dataclass(frozen=True)
class CandidateFamily:
    """What the FOS model of the loop may choose from: lags, degree, channels and columns.

    ``columns`` maps user-column names to their values over the whole record.
    """

    max_lag: int
    degree: int = 1
    exog_lags: Mapping[str, int] = field(default_factory=dict)
    columns: Mapping[str, np.ndarray] = field(default_factory=dict)

    def add(self, effect: Effect, channels: Mapping[str, np.ndarray], time: np.ndarray,
            train: slice) -> CandidateFamily:
        """This family with the candidates of ``effect`` added."""
        exog, cols, degree = dict(self.exog_lags), dict(self.columns), self.degree
        if effect.kind == "aux":
            x = channels[effect.channel]
            exog[effect.channel] = max(exog.get(effect.channel, 0), effect.max_lag)
            cols[f"sq({effect.channel})"] = (x - x[train].mean()) ** 2
        elif effect.kind == "periodic":
            phase = 2 * np.pi * effect.freq_hz * time
            cols[f"cos@{effect.freq_hz:.4f}Hz"] = np.cos(phase)
            cols[f"sin@{effect.freq_hz:.4f}Hz"] = np.sin(phase)
        elif effect.kind == "nonlinear":
            degree = max(degree, 2)
        elif effect.kind == "drift":
            values = trend_columns(time, "linear+exponential", effect.tau_s, 0.0)
            cols["t"], cols[f"exp(-t/{effect.tau_s:.4g}s)"] = values[:, 0], values[:, 1]
        else:  # step
            cols[f"step@{effect.time_s:.4g}s"] = (time >= effect.time_s).astype(float)
        return replace(self, degree=degree, exog_lags=exog, columns=cols)


def effects_from(findings: list[Finding], aux_max_lag: int) -> list[Effect]:
    """The candidate effects that the fired findings point to.

    A slow residual usually fires both the trend and the step test; both
    candidates are offered, and the evaluation segment, which a drift and a
    step extrapolate differently, chooses.
    """
    out = []
    for f in (f for f in findings if f.fired):
        if f.test == "aux":
            out.append(Effect("aux", channel=f.evidence["channel"],
                              max_lag=max(aux_max_lag, f.evidence["lag"]), evidence=f.to_dict()))
        elif f.test == "periodic":
            out.append(Effect("periodic", freq_hz=f.evidence["freq_hz"], evidence=f.to_dict()))
        elif f.test == "nonlinear":
            out.append(Effect("nonlinear", evidence=f.to_dict()))
        elif f.test == "step":
            out.append(Effect("step", time_s=f.evidence["time_s"], evidence=f.to_dict()))
        elif f.test == "trend":
            out.append(Effect("drift", form=f.evidence["form"], tau_s=f.evidence["tau_s"],
                              evidence=f.to_dict()))
    return out
