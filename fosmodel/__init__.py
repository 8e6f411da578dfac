"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors.

The names below are imported on first use (PEP 562), so that ``import fosmodel`` and the
command line's start (``fosmodel --version``, ``--help``) pay for scikit-learn, SciPy and
pandas only when a command or a user reaches for what needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ._version import __version__

#: The public names by the module each comes from.
_MODULES = {
    "core.candidates": ("CandidateSpec", "Term", "count_candidates", "generate_terms"),
    "core.exceptions": ("FOSModelError", "InputError", "NotFittedError", "UnstableModelWarning"),
    "core.fos": ("FOSResult", "StopRule", "fos"),
    "models.model": ("FOSModel",),
    "models.narx_features": ("NARXFeatures", "lagged_rows"),
    "models.regressor": ("FOSRegressor",),
}
_HOMES = {name: module for module, names in _MODULES.items() for name in names}

__all__ = [
    "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor", "FOSResult", "InputError",
    "NARXFeatures", "NotFittedError", "StopRule", "Term", "UnstableModelWarning",
    "count_candidates", "fos", "generate_terms", "lagged_rows", "__version__",
]

if TYPE_CHECKING:  # what the names are, for type checkers and editors
    from .core.candidates import CandidateSpec, Term, count_candidates, generate_terms
    from .core.exceptions import FOSModelError, InputError, NotFittedError, UnstableModelWarning
    from .core.fos import FOSResult, StopRule, fos
    from .models.model import FOSModel
    from .models.narx_features import NARXFeatures, lagged_rows
    from .models.regressor import FOSRegressor


def __getattr__(name: str) -> object:
    """Import a public name from its module the first time it is asked for."""
    if name not in _HOMES:
        raise AttributeError(f"module 'fosmodel' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """List the public names."""
    return sorted(__all__)
