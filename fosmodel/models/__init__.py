"""Fitted models: ``FOSModel`` (a FOS difference equation of a time series), the
scikit-learn ``FOSRegressor``, the AR and Gauss-Markov baselines (also about a local
level), their shared linear dynamics and free runs, and the text summaries they print.

Imports :mod:`fosmodel.core` only.
"""
