"""The residual loop: diagnostics of a fitted model's residual, the effect catalogue, the
out-of-sample judge, the loop itself and its report.

Imports the layers below it; never :mod:`fosmodel.study`.
"""
