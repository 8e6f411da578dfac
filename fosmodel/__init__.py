"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors."""

from ._version import __version__
from .candidates import CandidateSpec, Term, count_candidates, generate_terms
from .exceptions import FOSModelError, InputError, UnstableModelWarning
from .fos import FOSResult, StopRule, fos
from .model import FOSModel
from .regressor import FOSRegressor

__all__ = [
    "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor", "FOSResult", "InputError",
    "StopRule", "Term", "UnstableModelWarning", "count_candidates", "fos", "generate_terms",
    "__version__",
]
