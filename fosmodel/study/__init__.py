"""Model-order studies: the harness, its runners, reports and the temperature study.

The train / evaluate / predict harness, running its fits here or on a Dask cluster, the
study reports, and the temperature-chamber study.

Imports the layers below it; never :mod:`fosmodel.loop`.
"""
