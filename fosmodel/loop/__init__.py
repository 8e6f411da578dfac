"""The residual loop: diagnose a fitted model's residual, add an effect, judge, report.

The settings and the channels' roles, the diagnostics of a residual, the effect catalogue
(one module per kind, one registry), the out-of-sample judge at several outage lengths,
the loop on one record and over several sessions, the intervals of its before/after
numbers and its reports.

Imports the layers below it; never :mod:`fosmodel.study`.  Its public names are imported on
first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .closeloop import LoopResult, Step, close_loop, score_family
    from .config import LoopConfig
    from .diagnose import Finding, least_squares_spectrum
    from .driver_forms import DriverForms, slow_driver
    from .effects import CandidateFamily, Effect, make_effect
    from .handoff import Handoff, hand_off, refit_on_all
    from .loop_report import evaluation_text, write_loop_report
    from .record import LoopRecord
    from .sessions import Session, SessionsResult, close_sessions, score_sessions
    from .sessions_report import write_sessions_report
else:
    __getattr__, __dir__ = attach(__name__, {
        "closeloop": ("LoopResult", "Step", "close_loop", "score_family"),
        "config": ("LoopConfig",),
        "diagnose": ("Finding", "least_squares_spectrum"),
        "driver_forms": ("DriverForms", "slow_driver"),
        "effects": ("CandidateFamily", "Effect", "make_effect"),
        "handoff": ("Handoff", "hand_off", "refit_on_all"),
        "loop_report": ("evaluation_text", "write_loop_report"),
        "record": ("LoopRecord",),
        "sessions": ("Session", "SessionsResult", "close_sessions", "score_sessions"),
        "sessions_report": ("write_sessions_report",),
    })

__all__ = [
    "CandidateFamily", "DriverForms", "Effect", "Finding", "Handoff", "LoopConfig",
    "LoopRecord", "LoopResult", "Session", "SessionsResult", "Step", "close_loop",
    "close_sessions", "evaluation_text", "hand_off", "least_squares_spectrum", "make_effect",
    "refit_on_all", "score_family", "score_sessions", "slow_driver", "write_loop_report",
    "write_sessions_report",
]
