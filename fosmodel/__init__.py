"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors."""

from ._version import __version__
from .core.candidates import CandidateSpec, Term, count_candidates, generate_terms
from .core.exceptions import FOSModelError, InputError, NotFittedError, UnstableModelWarning
from .core.fos import FOSResult, StopRule, fos
from .models.model import FOSModel
from .models.narx_features import NARXFeatures, lagged_rows
from .models.regressor import FOSRegressor

__all__ = [
    "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor", "FOSResult", "InputError",
    "NARXFeatures", "NotFittedError", "StopRule", "Term", "UnstableModelWarning",
    "count_candidates", "fos", "generate_terms", "lagged_rows", "__version__",
]
