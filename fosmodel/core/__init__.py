"""The search itself: candidate terms, the FOS kernel and the correlations it runs on.

Candidate terms, the Fast Orthogonal Search kernel and its stopping rules, the correlation
providers (point by point, and Korenberg's fast path with its data-free plans), local-level
and derived columns, input checks and the package's errors, and how the work uses the
machine (one BLAS thread, independent calls in worker processes).

The lowest layer: it imports nothing else of fosmodel.
"""
