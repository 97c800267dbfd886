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
    double yaw;
    double x[9];  /* [p, v, a] of x, y, z */
    double P[6];  /* the covariance the axes share: m00, m01, m02, m11, m12, m22 */
    fc_paper_kf tilt;  /* the tilt stage */
    fc_estimate last;
    /* derived from params (PaperPositionKalmanFilter._configure) */
    double acc_var_density;
    double Q[6], R, Q_dt;
} fc_paper_poskf;

void fc_paper_poskf_init(fc_paper_poskf *f, const fc_paper_poskf_params *params);
void fc_paper_poskf_configure(fc_paper_poskf *f);
void fc_paper_poskf_reset(fc_paper_poskf *f);
fc_status fc_paper_poskf_step(fc_paper_poskf *f, const double acc[3], const double gyro[3],
                              double dt, fc_estimate *out);
long fc_paper_poskf_run(fc_paper_poskf *f, long n, const double *acc, const double *gyro,
                        const double *dt, fc_estimate *out, unsigned char *rejected);
fc_estimate fc_paper_poskf_estimate(const fc_paper_poskf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_paper_poskf_restored(fc_paper_poskf *f);

/* The equations (papers/position.py's functions of the same names): Q of one axis for a form
 * (FC_PAPER_POSKF_QR_FORM_*, upper triangle); one sample of the three [p, v, a] filters, with
 * the zero-velocity update (variance zupt_r) where with_zupt; R f - g e_z; the start from the
 * first sample, which initialises the tilt stage. */
void fc_paper_poskf_process_noise(int form, double q, double dt, double Q[6]);
void fc_paper_poskf_axis_filters(double x[9], double P[6], const double Q[6], double dt,
                                 const double acc[3], double r, int with_zupt, double zupt_r);
void fc_paper_poskf_level_acceleration(double ax, double ay, double az, double sr, double cr,
                                       double sp, double cp, double sy, double cy, double out[3]);
/* yaw_and_level_acceleration: yaw turned over dt in place, acc the level-frame acceleration. */
void fc_paper_poskf_yaw_and_level_acceleration(double roll, double pitch, double *yaw, double wy,
                                               double gz, const double a[3], double dt,
                                               double acc[3]);
void fc_paper_poskf_first_axis_states(fc_paper_kf *tilt, const double a[3], const double g[3],
                                      double dt, double acc_var_density, double x[9],
                                      double P[6]);

#endif /* FC_PAPER_POSKF_H */
