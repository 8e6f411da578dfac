% IMU noise from the Allan deviation of imu1.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps, gy_dps, gz_dps
%   RandomWalk: upper limit on gx_dps, gy_dps
gyro = gyroparams('NoiseDensity', [6.758046e-04 7.350294e-04 6.682519e-04], ...
    'BiasInstability', [1.694277e-04 1.615464e-04 1.316444e-04], ...
    'RandomWalk', [1.016811e-05 1.720681e-05 1.481301e-05]);
% accel: ax_g, ay_g, az_g
%   RandomWalk: upper limit on ay_g
accel = accelparams('NoiseDensity', [4.332885e-03 3.365447e-03 4.369747e-03], ...
    'BiasInstability', [3.669143e-03 3.167755e-03 2.880482e-03], ...
    'RandomWalk', [4.139965e-04 3.135267e-04 2.235223e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
