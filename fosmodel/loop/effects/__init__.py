"""The effect catalogue: one module per kind of effect, found through one registry.

================  ====================================================================
kind              candidates added
================  ====================================================================
``level``         local levels ``level@<tau>s`` of the output (:mod:`fosmodel.core.levels`):
                  the wandering bias as a stochastic level, over a grid of time constants
``driver``        slow part: the forms of a temperature, a voltage... (its powers, lags,
                  rate of change) as a fixed compensation, with the levels of the
                  compensated output; fast part: lags 0..K of the channel minus its own
                  local level (``<ch>_fast<T>s``)
``companion``     another axis of the same IMU, as a driver's fast part: only when asked
``periodic``      ``cos@<f>Hz`` and ``sin@<f>Hz`` at the found frequency
``nonlinear``     the cross-product degree raised to 2 (squares and products of the
                  output lags the test looked at)
``drift``         functions of time: ``t@s`` and ``exp(-t/<tau>s)`` (the warm-up found)
``step``          ``step@<time>s``, 0 before the step and 1 after it
================  ====================================================================

Every column is named so that it can be rebuilt from its name (:mod:`fosmodel.core.derived`).
Each kind is a module of this package whose class is registered (:func:`register`); every
module here is imported with the package, so a new kind is one new module.
"""

from __future__ import annotations

import importlib
import pkgutil

from .base import (
    Effect,
    Offer,
    effect_class,
    effect_from_dict,
    effects_from,
    kinds,
    make_effect,
    register,
    unregister,
)
from .base import (
    make as make,  # the older name, kept importable for existing code
)
from .family import CandidateFamily

for _module in pkgutil.iter_modules(__path__):
    importlib.import_module(f"{__name__}.{_module.name}")

__all__ = ["CandidateFamily", "Effect", "Offer", "effect_class",
           "effect_from_dict", "effects_from", "kinds", "make_effect", "register",
           "unregister"]
