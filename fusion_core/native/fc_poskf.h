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

void fc_poskf_init(fc_poskf *f, const fc_poskf_params *params);
void fc_poskf_configure(fc_poskf *f);
void fc_poskf_reset(fc_poskf *f);
fc_status fc_poskf_step(fc_poskf *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,
                        fc_estimate *out);
long fc_poskf_run(fc_poskf *f, long n, const fc_real *acc, const fc_real *gyro, const fc_real *dt,
                  fc_estimate *out, unsigned char *rejected);
long fc_poskf_run_columns(fc_poskf *f, long n, const fc_real *acc, const fc_real *gyro,
                          const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,
                          fc_real *pos, fc_real *vel, unsigned char *rejected);
fc_estimate fc_poskf_estimate(const fc_poskf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_poskf_restored(fc_poskf *f);

#endif /* FC_POSKF_H */
