"""Noise analysis of a record: Allan deviation and its fit, denoisers, error metrics.

The Allan deviation and its IEEE Std 952 fit (one axis or a whole IMU, with the Kalibr,
MATLAB and JSON exports), the denoisers of the paper protocol, and the error metrics every
study reports (equivalent position error, outages, bias).

Imports the layers below it (core, models, io).
"""
