"""fosmodel: Fast Orthogonal Search error models for MEMS inertial sensors."""

__version__ = "0.1.0"

from .candidates import CandidateSpec, Term, count_candidates, generate_terms  # noqa: E402
from .exceptions import FOSModelError, InputError, UnstableModelWarning  # noqa: E402
from .fos import FOSResult, StopRule, fos  # noqa: E402
from .model import FOSModel  # noqa: E402
from .regressor import FOSRegressor  # noqa: E402

__all__ = [
    "CandidateSpec", "FOSModel", "FOSModelError", "FOSRegressor", "FOSResult", "InputError",
    "StopRule", "Term", "UnstableModelWarning", "count_candidates", "fos", "generate_terms",
    "__version__",
]
