% IMU noise from the Allan deviation of imu2.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps, gy_dps, gz_dps
%   RandomWalk: upper limit on gx_dps, gy_dps, gz_dps
gyro = gyroparams('NoiseDensity', [6.676629e-04 7.234717e-04 6.395736e-04], ...
    'BiasInstability', [1.949253e-04 2.038216e-04 1.870106e-04], ...
    'RandomWalk', [1.318078e-05 1.893763e-05 1.933229e-05]);
% accel: ax_g, ay_g, az_g
%   RandomWalk: upper limit on ax_g
accel = accelparams('NoiseDensity', [3.955643e-03 3.082324e-03 4.200665e-03], ...
    'BiasInstability', [5.236523e-03 2.702857e-03 3.005559e-03], ...
    'RandomWalk', [4.052677e-04 3.355737e-04 3.262403e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
