/* fc_poskf.h: the recommended position Kalman filter with a zero-velocity update
 * (fusion_core/position.py, PositionKalmanFilter), the C twin. Safitri, Cahyadi, Firmansyah
 * eq. 20-29 (fc_paper_poskf.h), its tilt stage the papers' Kalman filter (fc_paper_kf) at
 * confirmed rest, its attitude outputs the recommended one's (fc_kf) on the same samples. */
#ifndef FC_POSKF_H
#define FC_POSKF_H

#include "fc_core.h"
#include "fc_kf.h"
#include "fc_paper_kf.h"
#include "fc_params.h"

typedef struct fc_poskf {
    fc_poskf_params params;
    fc_base base;
    /* PositionKalmanFilter.STATE */
    fc_real yaw;
    fc_real x[9];      /* [p, v, a] of x, y, z */
    fc_real P[6];      /* the covariance the axes share: m00, m01, m02, m11, m12, m22 */
    fc_real quiet_time;
    int stationary;
    /* the stationary queue: (quiet time, acc roll, acc pitch, turned roll, turned pitch) */
    fc_real pending[FC_POSKF_PENDING_MAX][5];
    int pending_head, pending_count;
    fc_real turned[2];
    fc_real f_mean[3];
    int aligned;       /* the tilt stage has taken a confirmed rest's accelerometer */
    fc_paper_kf tilt;  /* the tilt stage */
    fc_kf att;         /* the attitude outputs */
    fc_estimate last;
    /* derived from params (PositionKalmanFilter._configure) */
    fc_real acc_var_density, zupt_var, gyro_var_density;
    fc_real Q[6], R, Q_dt;
    /* tilt_sines' cache (never saved): the tilt angles sines[0..1] and their sines and cosines */
    fc_real sines[6];
} fc_poskf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_poskf);

#endif /* FC_POSKF_H */
