/* fc_ukf.h: the recommended unscented Kalman filter on the gravity direction with three
 * gyro-bias states (fusion_core/ukf.py, UnscentedKalmanFilter), the C twin. Duong Quoc et al.
 * eq. 14-17 (fc_paper_ukf.h) with the mechanisms for real sensors of the Python class's
 * docstring. */
#ifndef FC_UKF_H
#define FC_UKF_H

#include "fc_core.h"
#include "fc_params.h"

/* ukf.ACC_GATE: no update while ||f|/g - 1| is at or above it */
#define FC_UKF_ACC_GATE 1.0

typedef struct fc_ukf {
    fc_ukf_params params;
    fc_base base;
    /* UnscentedKalmanFilter.STATE */
    fc_real x[6];      /* X (the gravity direction, 3), b (the gyro bias, 3) */
    fc_real P[21];     /* the covariance's lower triangle, row by row */
    fc_real meas[FC_MEAS_SIZE];  /* the measured vector (acc_lowpass > 0; measured_vector) */
    fc_real rest[FC_REST_SIZE];
    fc_estimate last;
    /* derived from params (UnscentedKalmanFilter._configure) */
    fc_real gamma, w, w_mu, q_gyro, q_bias, r_acc;
    fc_real q_rotation, dist_tau;  /* UnscentedKalmanFilter._adaptive */
    fc_meas_constants measure;  /* UnscentedKalmanFilter._measure */
    fc_real longest2, rail_var;
    fc_real bias_lo2, bias_hi2, cos_innovation, cos_gross;
} fc_ukf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_ukf);

#endif /* FC_UKF_H */
