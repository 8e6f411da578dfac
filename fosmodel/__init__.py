"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors.

The public names are imported on first use (PEP 562): ``import fosmodel`` itself imports
nothing heavy, so that the command line holds Ctrl-C before numpy, pandas and scikit-learn
are loaded (a second or two) as well as after.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ._version import __version__

if TYPE_CHECKING:
    from .core.candidates import CandidateSpec, Term, count_candidates, generate_terms
    from .core.exceptions import FOSModelError, InputError, NotFittedError, UnstableModelWarning
    from .core.fos import FOSResult, StopRule, fos
    from .models.model import FOSModel
    from .models.narx_features import NARXFeatures, lagged_rows
    from .models.regressor import FOSRegressor

#: Each public name and the module it comes from.
_HOMES = {
    **dict.fromkeys(["CandidateSpec", "Term", "count_candidates", "generate_terms"],
                    "core.candidates"),
    **dict.fromkeys(["FOSModelError", "InputError", "NotFittedError", "UnstableModelWarning"],
                    "core.exceptions"),
    **dict.fromkeys(["FOSResult", "StopRule", "fos"], "core.fos"),
    "FOSModel": "models.model",
    **dict.fromkeys(["NARXFeatures", "lagged_rows"], "models.narx_features"),
    "FOSRegressor": "models.regressor",
}

__all__ = [
    "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor", "FOSResult", "InputError",
    "NARXFeatures", "NotFittedError", "StopRule", "Term", "UnstableModelWarning",
    "count_candidates", "fos", "generate_terms", "lagged_rows", "__version__",
]


def __getattr__(name: str) -> object:
    """Import a public name from its module on first use."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{home}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """List the public names with the module's own."""
    return sorted({*globals(), *__all__})
