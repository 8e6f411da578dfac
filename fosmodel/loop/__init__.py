"""The residual loop: diagnose a fitted model's residual, add an effect, judge, report.

Diagnostics of a fitted model's residual, the effect catalogue, the out-of-sample judge,
the loop itself and its report.

Imports the layers below it; never :mod:`fosmodel.study`.
"""
