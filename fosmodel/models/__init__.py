"""Fitted models: FOS difference equations, the AR and Gauss-Markov baselines.

``FOSModel`` (a FOS difference equation of a time series, also in the raw signals), the
scikit-learn ``FOSRegressor`` and the ``NARXFeatures`` that feed it lagged candidates, the
AR and Gauss-Markov baselines (also about a local level), their shared linear dynamics and
free runs.

Imports :mod:`fosmodel.core` and :mod:`fosmodel.typeset` (the summaries they print) only.
"""
