/* fc_paper_poskf.h: the paper's position Kalman filter (fusion_core/papers/position.py,
 * PaperPositionKalmanFilter), the C twin. Safitri, Cahyadi, Firmansyah eq. 20-29, with the tilt
 * from the papers' Kalman filter (fc_paper_kf) run on the same samples. Its equations are
 * public: the recommended filter (fc_poskf.c) is built on them. */
#ifndef FC_PAPER_POSKF_H
#define FC_PAPER_POSKF_H

#include "fc_core.h"
#include "fc_paper_kf.h"
#include "fc_params.h"

typedef struct fc_paper_poskf {
    fc_paper_poskf_params params;
    fc_base base;
    /* PaperPositionKalmanFilter.STATE */
    fc_real yaw;
    fc_real x[9];  /* [p, v, a] of x, y, z */
    fc_real P[6];  /* the covariance the axes share: m00, m01, m02, m11, m12, m22 */
    fc_paper_kf tilt;  /* the tilt stage */
    fc_estimate last;
    /* derived from params (PaperPositionKalmanFilter._configure) */
    fc_real acc_var_density;
    fc_real Q[6], R, Q_dt;
} fc_paper_poskf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_paper_poskf);
/* The position and velocity of the [p, v, a] axis states x (x, y, z axes in turn) into e. */
void fc_paper_poskf_put_axes(const fc_real x[9], fc_estimate *e);

/* The equations (papers/position.py's functions of the same names): Q of one axis for a form
 * (FC_PAPER_POSKF_QR_FORM_*, upper triangle); one sample of the three [p, v, a] filters, with
 * the zero-velocity update (variance zupt_r) where with_zupt; R f - g e_z; the start from the
 * first sample, which initialises the tilt stage. */
void fc_paper_poskf_process_noise(int form, fc_real q, fc_real dt, fc_real Q[6]);
void fc_paper_poskf_axis_filters(fc_real x[9], fc_real P[6], const fc_real Q[6], fc_real dt,
                                 const fc_real acc[3], fc_real r, int with_zupt, fc_real zupt_r);
void fc_paper_poskf_level_acceleration(fc_real ax, fc_real ay, fc_real az, fc_real sr, fc_real cr,
                                       fc_real sp, fc_real cp, fc_real sy, fc_real cy, fc_real out[3]);
/* yaw_and_level_acceleration: yaw turned over dt in place, acc the level-frame acceleration;
 * sc: the sines and cosines of roll and pitch (sin r, cos r, sin p, cos p), or NULL. */
void fc_paper_poskf_yaw_and_level_acceleration(fc_real roll, fc_real pitch, fc_real *yaw, fc_real wy,
                                               fc_real gz, const fc_real a[3], fc_real dt,
                                               const fc_real sc[4], fc_real acc[3]);
void fc_paper_poskf_first_axis_states(fc_paper_kf *tilt, const fc_real a[3], const fc_real g[3],
                                      fc_real dt, fc_real acc_var_density, fc_real x[9],
                                      fc_real P[6]);

#endif /* FC_PAPER_POSKF_H */
