% IMU noise from the Allan deviation of unmoved-with-x-pointing-forward-10min.csv.gz by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps, gy_dps, gz_dps
%   BiasInstability: upper limit on gy_dps, gz_dps
%   RandomWalk: upper limit on gx_dps, gy_dps, gz_dps
gyro = gyroparams('NoiseDensity', [2.225717e-04 1.608539e-04 1.668030e-04], ...
    'BiasInstability', [8.436020e-05 3.539897e-05 3.353077e-05], ...
    'RandomWalk', [2.445200e-05 1.205545e-05 1.109887e-05]);
% accel: ax_g, ay_g, az_g
%   BiasInstability: upper limit on ax_g, ay_g, az_g
%   RandomWalk: upper limit on ax_g, ay_g, az_g
accel = accelparams('NoiseDensity', [2.962396e-03 3.077139e-03 4.895667e-03], ...
    'BiasInstability', [8.565163e-04 6.991535e-04 1.255882e-03], ...
    'RandomWalk', [1.388269e-04 2.448172e-04 3.607221e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 99.3171, 'Gyroscope', gyro, 'Accelerometer', accel);
