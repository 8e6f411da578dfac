"""The search itself: candidate terms, the FOS kernel and the correlations it runs on.

Candidate terms, the Fast Orthogonal Search kernel and its stopping rules, the correlation
providers (point by point, and Korenberg's fast path with its data-free plans), local-level
and derived columns, input checks and the package's errors, and how the work uses the
machine (one BLAS thread, independent calls in worker processes) and where a fit's time
goes (timed parts).

The lowest layer: it imports nothing else of fosmodel.  Its public names are imported on
first use (:mod:`fosmodel._lazy`); ``fos()`` itself is :func:`fosmodel.fos` (here
``fosmodel.core.fos`` is its module).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .candidates import (
        CandidateSpec,
        Term,
        count_candidates,
        evaluate_terms,
        generate_terms,
    )
    from .correlations import LagCorrelations
    from .derived import Description, derive, describe, power_name
    from .exceptions import (
        FitWarning,
        FOSModelError,
        InputError,
        NotFittedError,
        UnstableModelWarning,
    )
    from .fos import DataCorrelations, FOSResult, StopRule, center
    from .levels import levels_for
    from .parallel import in_workers
    from .shapes import clear_plans, layout
    from .timing import PartTimes, timed_parts
else:
    __getattr__, __dir__ = attach(__name__, {
        "candidates": ("CandidateSpec", "Term", "count_candidates", "evaluate_terms",
                       "generate_terms"),
        "correlations": ("LagCorrelations",),
        "derived": ("Description", "derive", "describe", "power_name"),
        "exceptions": ("FOSModelError", "FitWarning", "InputError", "NotFittedError",
                       "UnstableModelWarning"),
        "fos": ("DataCorrelations", "FOSResult", "StopRule", "center"),
        "levels": ("levels_for",),
        "parallel": ("in_workers",),
        "shapes": ("clear_plans", "layout"),
        "timing": ("PartTimes", "timed_parts"),
    })

__all__ = [
    "CandidateSpec", "DataCorrelations", "Description", "FOSModelError", "FOSResult",
    "FitWarning", "InputError", "LagCorrelations", "NotFittedError", "PartTimes", "StopRule",
    "Term", "UnstableModelWarning", "center", "clear_plans", "count_candidates", "derive",
    "describe", "evaluate_terms", "generate_terms", "in_workers", "layout", "levels_for",
    "power_name", "timed_parts",
]
