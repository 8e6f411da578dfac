% IMU noise from the Allan deviation of gyro_x.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gyro_x
%   BiasInstability: upper limit on gyro_x
%   RandomWalk: upper limit on gyro_x
gyro = gyroparams('NoiseDensity', 6.431337e-04, ...
    'BiasInstability', 7.875292e-05, ...
    'RandomWalk', 4.344060e-06);
