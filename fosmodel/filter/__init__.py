"""Error models in a navigation filter: shaping filters, a Kalman filter, gyro arrays.

Fitted models and Allan fits as state-space shaping filters, a small linear Kalman filter,
and gyro arrays (averaging and the virtual gyro).

Imports the layers below it (core, models, io, noise).
"""
