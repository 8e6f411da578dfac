"""Error models in a navigation filter: fitted models and Allan fits as state-space shaping
filters, a small linear Kalman filter, and gyro arrays (averaging and the virtual gyro).

Imports the layers below it (core, models, io, noise).
"""
