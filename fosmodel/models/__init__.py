"""Fitted models: FOS difference equations, the AR and Gauss-Markov baselines.

``FOSModel`` (a FOS difference equation of a time series, also in the raw signals), the
scikit-learn ``FOSRegressor`` and the ``NARXFeatures`` that feed it lagged candidates, the
AR and Gauss-Markov baselines (also about a local level), their shared linear dynamics and
free runs.

Imports :mod:`fosmodel.core` and :mod:`fosmodel.typeset` (the summaries they print) only.
Its public names are imported on first use (:mod:`fosmodel._lazy`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from .baselines import ARModel, GaussMarkovModel
    from .compensation import compensation_series
    from .levelar import LocalLevelAR
    from .model import FOSModel
    from .narx_features import NARXFeatures, lagged_rows
    from .regressor import FOSRegressor
else:
    __getattr__, __dir__ = attach(__name__, {
        "baselines": ("ARModel", "GaussMarkovModel"),
        "compensation": ("compensation_series",),
        "levelar": ("LocalLevelAR",),
        "model": ("FOSModel",),
        "narx_features": ("NARXFeatures", "lagged_rows"),
        "regressor": ("FOSRegressor",),
    })

__all__ = ["ARModel", "FOSModel", "FOSRegressor", "GaussMarkovModel", "LocalLevelAR",
           "NARXFeatures", "compensation_series", "lagged_rows"]
