% IMU noise from the Allan deviation of imu6.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps, gy_dps, gz_dps
%   RandomWalk: upper limit on gx_dps, gy_dps, gz_dps
gyro = gyroparams('NoiseDensity', [6.969431e-04 7.236375e-04 6.611576e-04], ...
    'BiasInstability', [1.328612e-04 1.853012e-04 1.636356e-04], ...
    'RandomWalk', [1.340445e-05 1.097294e-05 1.113709e-05]);
% accel: ax_g, ay_g, az_g
%   RandomWalk: upper limit on ax_g
accel = accelparams('NoiseDensity', [4.245304e-03 3.439538e-03 4.570584e-03], ...
    'BiasInstability', [3.843696e-03 2.834012e-03 2.769096e-03], ...
    'RandomWalk', [3.918491e-04 2.514127e-04 2.780146e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
