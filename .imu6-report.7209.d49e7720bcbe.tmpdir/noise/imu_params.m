% IMU noise from the Allan deviation of imu6.csv by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx_dps
%   RandomWalk: upper limit on gx_dps
gyro = gyroparams('NoiseDensity', 5.705514e-04, ...
    'BiasInstability', 2.270662e-04, ...
    'RandomWalk', 3.900824e-05);
% accel: ax_mps2
%   RandomWalk: upper limit on ax_mps2
accel = accelparams('NoiseDensity', 3.313915e-03, ...
    'BiasInstability', 3.082506e-03, ...
    'RandomWalk', 7.232944e-04);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
