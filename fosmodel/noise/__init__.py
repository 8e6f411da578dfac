"""Noise analysis of a record: Allan deviation and its fit, denoisers, error metrics.

The Allan deviation (``allan``), its IEEE Std 952 fit (``allan_fit``) and their figure and
files (``allan_report``), for one axis or a whole IMU (``imu_noise``, with the Kalibr, MATLAB
and JSON exports), the denoisers of the paper protocol, and the error metrics every
study reports (equivalent position error, outages, bias).

Imports the layers below it (core, typeset, models, io).
"""
