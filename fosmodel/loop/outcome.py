"""What the residual loop did, on one record or over several sessions, as one protocol.

:class:`LoopOutcome` is what the reports, the figure, the hand-off and the command line
read of a loop's result; :class:`~fosmodel.loop.closeloop.LoopResult` (one record) and
:class:`~fosmodel.loop.sessions.SessionsResult` (several sessions) carry it, each with
what only it has (one record's segments and residuals, each session's scores and
constant).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..models.bound import BoundModel
from .config import LoopConfig
from .diagnose import Finding
from .intervals import Ratio
from .roles import Roles
from .rounds import Rejected, Step
from .scores import Scores


class LoopOutcome:
    """A loop's result: the starting and final models, their scores, the steps between.

    ``before_scores``/``after_scores`` are the predicted errors of the starting and the
    final model (:attr:`before`/:attr:`after` their numbers, pooled over sessions);
    ``steps`` the kept effects in order; ``rejected`` the candidates that did not go in;
    ``findings_before``/``findings_after`` the diagnostics of the first and the last model;
    ``notes`` what the report must say besides.
    """

    config: LoopConfig
    roles: Roles
    before_scores: Scores
    after_scores: Scores
    steps: Sequence[Step]
    rejected: list[Rejected]
    findings_before: list[Finding]
    findings_after: list[Finding]
    base_model: BoundModel
    final_model: BoundModel
    level_taus: tuple[float, ...]
    notes: list[str]

    def ratios(self) -> list[Ratio]:
        """Return the final model's ratios to the starting one, each with its interval."""
        raise NotImplementedError

    def worse(self) -> list[str]:
        """Return the ratios whose interval lies above 1: what the final model made worse."""
        return [r.text() for r in self.ratios() if r.verdict == "worse"]

    def to_json_dict(self) -> dict[str, Any]:
        """Return the result as the command line's JSON output holds it."""
        raise NotImplementedError

    def handed_on(self) -> tuple[BoundModel, str]:
        """Return the model to save or export, and which it is in words.

        The final model, or the starting one when the effects kept made the prediction
        segment worse beyond an interval: the loop never hands on a model that makes
        unseen data worse.  ``close-loop --model`` and ``imu`` save the same one.
        """
        if self.steps and self.worse():
            return self.base_model, ("the loop's starting model (its effects made the "
                                     "prediction segment worse)")
        return self.final_model, "the loop's final model"

    @property
    def before(self) -> Scores:
        """The starting model's predicted errors (``before_scores``)."""
        return self.before_scores

    @property
    def after(self) -> Scores:
        """The final model's predicted errors (``after_scores``)."""
        return self.after_scores
