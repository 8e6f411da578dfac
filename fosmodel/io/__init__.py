"""Records in and results out: reading and checking records, writing results atomically.

Reading and checking CSV / .npy / Parquet files and their time base, the bundled sample
record, and the atomic writer every output goes through (tables and figures included).

Imports :mod:`fosmodel.core`, :mod:`fosmodel.typeset` and :mod:`fosmodel.models` only.
"""
