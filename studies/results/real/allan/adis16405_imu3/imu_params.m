% IMU noise from the Allan deviation of imu3.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps, gy_dps, gz_dps
%   RandomWalk: upper limit on gx_dps, gy_dps, gz_dps
gyro = gyroparams('NoiseDensity', [6.941656e-04 7.303143e-04 6.712950e-04], ...
    'BiasInstability', [1.799343e-04 1.997117e-04 1.830229e-04], ...
    'RandomWalk', [6.849172e-06 1.168856e-05 1.119300e-05]);
% accel: ax_g, ay_g, az_g
%   RandomWalk: upper limit on ay_g
accel = accelparams('NoiseDensity', [3.986339e-03 3.253204e-03 4.531895e-03], ...
    'BiasInstability', [3.748217e-03 2.873652e-03 2.549728e-03], ...
    'RandomWalk', [4.878562e-04 2.654060e-04 2.985347e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
