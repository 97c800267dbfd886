/* fc_kf.h: the recommended two-state [angle, bias] Kalman filter for roll and for pitch
 * (fusion_core/kalman.py, AngleBiasKalmanFilter), the C twin. Gui et al. 2015 eq. 5-26, Das &
 * Mary eq. 16-27 (fc_paper_kf.h) with the mechanisms for real sensors of the Python class's
 * docstring. */
#ifndef FC_KF_H
#define FC_KF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_kf {
    fc_kf_params params;
    fc_base base;
    /* AngleBiasKalmanFilter.STATE */
    fc_real roll, pitch, bias_x, bias_y;
    fc_real P_roll[4], P_pitch[4];   /* [P00, P01, P10, P11] of each axis */
    fc_real bias_z, P_z;
    fc_real meas[FC_MEAS_SIZE];  /* the measured vector (acc_lowpass > 0; measured_vector) */
    fc_real rest[FC_REST_SIZE];
    fc_real q_att[4];
    int face;
    fc_real gain_roll[2], gain_pitch[2];  /* the last update's gains (diagnostics) */
    fc_estimate last;
    fc_real r_step;  /* this step's measurement variance (the measured vector's noise) */
    fc_real q_step;  /* this step's angle process noise (propagate) */
    /* derived from params (AngleBiasKalmanFilter._configure) */
    fc_real q_angle, q_bias, r, gate_low2, gate_high2, acc_tau;
    fc_real q_rotation, dist_tau;  /* AngleBiasKalmanFilter._adaptive */
    fc_meas_constants measure;  /* AngleBiasKalmanFilter._measure */
    fc_real longest2, rail_var;
    fc_real rest_time, rest_gyro, rest_acc, gyro_var, rest_bias_bound;
    fc_real bias_lo2, bias_hi2;
} fc_kf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_kf);
/* Estimator.step_prepared (fc_step_prepared): the position filter's attitude kf takes the samples
 * the position filter has checked and conditioned, with its rail flag */
fc_status fc_kf_step_prepared(fc_kf *f, const fc_real a[3], const fc_real g[3], fc_real dt,
                              int clipped, fc_estimate *out);

#endif /* FC_KF_H */
