/* fc_sensor.h: the MEMS IMU error model (fusion_core/sensor.py, ImuSensorModel), the C twin:
 * white noise, per-run turn-on biases and scale / cross-axis errors, bias instability and random
 * walk, the MPU-6050's digital low-pass filter, saturation, quantisation, timestamp jitter; the
 * noise counter-based (fc_noise.h), so sample k's noise depends on (seed, k) only. */
#ifndef FC_SENSOR_H
#define FC_SENSOR_H

#include <stdint.h>

#include "fc_params.h"

#define FC_SENSOR_NORMALS 19      /* sensor.N_NORMALS */
#define FC_SENSOR_RUN_NORMALS 30  /* sensor.N_RUN_NORMALS */

/* LowPass2: a 2nd-order Butterworth low-pass (or a pure delay) on three channels */
typedef struct fc_lowpass2 {
    double bandwidth, delay, h;
    double coef[5];
    int n_coef;                   /* 1: the delay form, 5: the biquad */
    int started;                  /* the state holds values (the first sample sets it) */
    double state[3][4];           /* per channel: x1, x2, y1, y2 */
} fc_lowpass2;

typedef struct fc_sensor {
    fc_sensor_params params;
    uint64_t noise_key;
    /* ImuSensorModel._STATE */
    long k;
    double gyro_turn_on[3], acc_turn_on[3];
    double gyro_matrix[3][3], acc_matrix[3][3];
    double gyro_walk[3], acc_walk[3], gyro_gm[3], acc_gm[3];
    int has_omega_prev;
    double omega_prev[3];
    double time_error;
    int filtered;                 /* dlpf_cfg >= 0 */
    fc_lowpass2 gyro_filter, acc_filter;
} fc_sensor;

void fc_sensor_init(fc_sensor *s, const fc_sensor_params *params);
void fc_sensor_reset(fc_sensor *s);
/* The gyro's total bias now [rad/s] (the sensor FMU's true_bias outputs). */
void fc_sensor_gyro_bias(const fc_sensor *s, double out[3]);
/* The sample taken at the end of an interval h > 0: acc, gyro, dt; -1 (nothing done) for h <= 0. */
int fc_sensor_sample(fc_sensor *s, const double omega[3], const double f[3], double h,
                     double acc[3], double gyro[3], double *dt);
/* n samples: omega, f [n][3], h [n] in; acc, gyro [n][3], dt [n], the true gyro bias [n][3]
 * out. Returns 0, or -1 at the first h <= 0 (the samples before it are done). */
int fc_sensor_run(fc_sensor *s, long n, const double *omega, const double *f, const double *h,
                  double *acc, double *gyro, double *dt, double *gyro_bias);

#endif /* FC_SENSOR_H */
