"""The residual loop: diagnose a fitted model's residual, add an effect, judge, report.

Diagnostics of a fitted model's residual, the effect catalogue, the out-of-sample judge,
the loop itself and its report.

Imports the layers below it; never :mod:`fosmodel.study`.  Its public names are imported on
first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .closeloop import LoopConfig, LoopResult, Step, close_loop, score_family
    from .diagnose import Finding, least_squares_spectrum
    from .effects import CandidateFamily, Effect
    from .loop_report import evaluation_text, write_loop_report
else:
    __getattr__, __dir__ = attach(__name__, {
        "closeloop": ("LoopConfig", "LoopResult", "Step", "close_loop", "score_family"),
        "diagnose": ("Finding", "least_squares_spectrum"),
        "effects": ("CandidateFamily", "Effect"),
        "loop_report": ("evaluation_text", "write_loop_report"),
    })

__all__ = [
    "CandidateFamily", "Effect", "Finding", "LoopConfig", "LoopResult", "Step", "close_loop",
    "evaluation_text", "least_squares_spectrum", "score_family", "write_loop_report",
]
