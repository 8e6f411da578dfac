"""The undeclared effects of a synthetic record as fosmodel effects: what the residual loop
should find, and which of them are slow (judged on the outage error rather than one step).
"""

from __future__ import annotations

from fosmodel.core.candidates import OUTPUT, Term
from fosmodel.loop.effects import Effect, make_effect

#: Source kinds whose effect is slow: a one-step predictor barely sees them.
SLOW_KINDS = ("temperature_bias", "drift", "bias_step", "random_walk")


def true_effects(truth: dict) -> list[tuple[Effect, bool]]:
    """``(effect, slow)`` for each undeclared source that has an effect kind, in source order.

    An input (temperature, another sensor) is offered with the lags it has in the
    one-step equation of the record: its own lags plus the order of the record's
    recursive noise, through which it is seen.
    """
    sources = truth["sources"]
    ar_order = max((lag for s in sources for t in (s["terms"] or [])
                    for ch, lag in Term.parse(t["term"]).factors if ch == OUTPUT), default=0)
    out = []
    for s in sources:
        if s["declared"]:
            continue
        p, kind = s["params"], s["kind"]
        if kind in ("temperature_bias", "aux_input"):
            lags = [lag for t in s["terms"] or [] for ch, lag in Term.parse(t["term"]).factors
                    if ch == p["input"]]
            effect = make_effect("aux", channel=p["input"], max_lag=max(lags, default=0) + ar_order)
        elif kind == "vibration":
            effect = make_effect("periodic", freq_hz=p["freq_hz"])
        elif kind == "nonlinear_ar":
            effect = make_effect("nonlinear")
        elif kind == "drift":
            effect = make_effect("drift", form="linear+exponential", tau_s=p["warmup_tau_s"])
        elif kind == "bias_step":  # one effect per step
            out += [(make_effect("step", time_s=step["time_s"]), True) for step in p["steps"][:-1]]
            effect = make_effect("step", time_s=p["steps"][-1]["time_s"])
        elif kind == "random_walk" and s["channel"] == truth["target"]:
            effect = make_effect("level")  # a wandering bias: its optimal predictor is a level
        else:
            continue
        out.append((effect, kind in SLOW_KINDS))
    return out
