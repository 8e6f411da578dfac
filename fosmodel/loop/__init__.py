"""The residual loop: diagnose a fitted model's residual, add an effect, judge, report.

The settings and the channels' roles, the diagnostics of a residual, the effect catalogue
(one module per kind, one registry), the out-of-sample judge at several outage lengths,
the loop on one record and over several sessions, the intervals of its before/after
numbers and its reports.

Imports the layers below it; never :mod:`fosmodel.study`.
"""
