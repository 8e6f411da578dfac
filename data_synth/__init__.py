"""Synthetic MEMS gyro and accelerometer error records with known ground truth.

Build a record from named presets::

    from data_synth import make_scenario, make_sessions, write_record
    rec = make_scenario("paper_gyro_y", duration=600, seed=1)
    write_record(rec, "out/gyro.csv")          # + out/gyro.truth.json
    s1, s2, s3 = make_sessions("temperature_sessions", seed=1)   # one sensor, three days

or compose one from sources::

    from data_synth import compose, GaussMarkov, TemperatureBias, WarmUp, WhiteNoise
    rec = compose([GaussMarkov(0.5, 0.02, order=2),
                   WarmUp(22, 12, 90, channel="temp_c"),
                   TemperatureBias((0, 0.02, 0.001), declared=False)],
                  duration=300, rate=100, seed=0, target="gyro_x",
                  column_units={"temp_c": "degC"})

Modules: :mod:`~data_synth.units` (conversions), :mod:`~data_synth.sources`
(stochastic sources), :mod:`~data_synth.arrays` (correlated gyro arrays),
:mod:`~data_synth.effects` (biases, inputs, functions of time, quantization),
:mod:`~data_synth.profiles` (temperature and rate profiles),
:mod:`~data_synth.terms` (exact lag models in fosmodel's term grammar),
:mod:`~data_synth.orientation` (gravity and earth rate of a static attitude),
:mod:`~data_synth.imu` (six-axis sweep sessions, axes with shared noise),
:mod:`~data_synth.record` (SynthRecord, compose), :mod:`~data_synth.scenarios`
(presets, sessions), :mod:`~data_synth.io` (CSV + truth sidecar), :mod:`~data_synth.cli`.

The names below are imported on first use (PEP 562): ``fosmodel`` builds its command line,
``synth`` included, without loading the generator.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

#: The public names by the module each comes from.
_MODULES = {
    "arrays": ("CorrelatedGaussMarkov", "CorrelatedRandomWalk", "CorrelatedWhiteNoise"),
    "base": ("Source",),
    "effects": ("AuxInput", "BiasStep", "ConstantBias", "Drift", "Knocks", "Quantizer",
                "ScaleFactorError", "TemperatureBias", "TurnOnBias", "Vibration"),
    "io": ("session_paths", "truth_path", "write_record", "write_sessions"),
    "orientation": ("Orientation",),
    "profiles": ("RoomCycle", "StepProfile", "Sweep", "WarmUp"),
    "record": ("SynthRecord", "compose"),
    "scenarios": ("list_scenarios", "make_scenario", "make_sessions"),
    "sources": ("ARProcess", "BiasInstability", "GaussMarkov", "NonlinearAR", "RandomWalk",
                "TemperatureWhiteNoise", "WhiteNoise"),
    "terms": ("evaluate",),
}
_HOMES = {name: module for module, names in _MODULES.items() for name in names}

if TYPE_CHECKING:  # what the names are, for type checkers and editors
    from data_synth.arrays import CorrelatedGaussMarkov, CorrelatedRandomWalk, CorrelatedWhiteNoise
    from data_synth.base import Source
    from data_synth.effects import (
        AuxInput,
        BiasStep,
        ConstantBias,
        Drift,
        Knocks,
        Quantizer,
        ScaleFactorError,
        TemperatureBias,
        TurnOnBias,
        Vibration,
    )
    from data_synth.io import session_paths, truth_path, write_record, write_sessions
    from data_synth.orientation import Orientation
    from data_synth.profiles import RoomCycle, StepProfile, Sweep, WarmUp
    from data_synth.record import SynthRecord, compose
    from data_synth.scenarios import list_scenarios, make_scenario, make_sessions
    from data_synth.sources import (
        ARProcess,
        BiasInstability,
        GaussMarkov,
        NonlinearAR,
        RandomWalk,
        TemperatureWhiteNoise,
        WhiteNoise,
    )
    from data_synth.terms import evaluate

__all__ = [
    "ARProcess",
    "AuxInput",
    "BiasInstability",
    "BiasStep",
    "ConstantBias",
    "CorrelatedGaussMarkov",
    "CorrelatedRandomWalk",
    "CorrelatedWhiteNoise",
    "Drift",
    "GaussMarkov",
    "Knocks",
    "NonlinearAR",
    "Orientation",
    "Quantizer",
    "RandomWalk",
    "RoomCycle",
    "ScaleFactorError",
    "Source",
    "StepProfile",
    "Sweep",
    "SynthRecord",
    "TemperatureBias",
    "TemperatureWhiteNoise",
    "TurnOnBias",
    "Vibration",
    "WarmUp",
    "WhiteNoise",
    "compose",
    "evaluate",
    "list_scenarios",
    "make_scenario",
    "make_sessions",
    "session_paths",
    "truth_path",
    "write_record",
    "write_sessions",
]


def __getattr__(name: str) -> object:
    """Import a public name from its module the first time it is asked for."""
    if name not in _HOMES:
        raise AttributeError(f"module 'data_synth' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"data_synth.{_HOMES[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """List the public names."""
    return sorted(__all__)
