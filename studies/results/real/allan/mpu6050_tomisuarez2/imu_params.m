% IMU noise from the Allan deviation of static_7min.csv by fosmodel 0.1.0.
% NoiseDensity = N, BiasInstability = B (Allan floor 0.664 B), RandomWalk = K; one value per axis in the order given,
% or the largest over the axes when a sensor has not exactly three. Upper limits (terms not resolved) are marked.
% gyro: gx, gy, gz
%   BiasInstability: upper limit on gx, gy, gz
%   RandomWalk: upper limit on gx, gy, gz
gyro = gyroparams('NoiseDensity', [1.271369e-04 1.956988e-04 1.620351e-04], ...
    'BiasInstability', [4.498349e-05 6.114593e-05 3.982062e-05], ...
    'RandomWalk', [8.561256e-06 1.512018e-05 1.617669e-05]);
% accel: ax, ay, az
%   BiasInstability: upper limit on ax, ay, az
%   RandomWalk: upper limit on ax, ay, az
accel = accelparams('NoiseDensity', [3.212096e-03 2.949834e-03 4.475975e-03], ...
    'BiasInstability', [6.512950e-04 1.065297e-03 1.414010e-03], ...
    'RandomWalk', [3.121044e-04 1.672452e-04 4.897864e-04]);
imu = imuSensor('accel-gyro', 'SampleRate', 100, 'Gyroscope', gyro, 'Accelerometer', accel);
