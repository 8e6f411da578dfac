"""Records in and results out: reading and checking records, writing results atomically.

The formats a record is read from (one table, :mod:`fosmodel.io.formats`) and a reader for
each (CSV, .npy, Parquet, ROS bags, PX4 ULog), the checks and repairs of its values, time base
and outliers, the bundled sample record, fitted models as files, and the atomic writer every
output goes through (tables and figures included).

Imports :mod:`fosmodel.core`, :mod:`fosmodel.typeset` and :mod:`fosmodel.models` only.
"""
