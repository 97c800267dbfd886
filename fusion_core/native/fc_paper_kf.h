/* fc_paper_kf.h: the papers' two-state [angle, bias] Kalman filter for roll and for pitch
 * (fusion_core/papers/kalman.py, PaperKalmanFilter), the C twin. Gui et al. 2015 eq. 5-26, Das &
 * Mary eq. 16-27. Its equations are public: the recommended filter (fc_kf.c) is built on them. */
#ifndef FC_PAPER_KF_H
#define FC_PAPER_KF_H

#include "fc_core.h"
#include "fc_params.h"

#include <string.h>

typedef struct fc_paper_kf {
    fc_paper_kf_params params;
    fc_base base;
    /* PaperKalmanFilter.STATE */
    fc_real roll, pitch, bias_x, bias_y;
    fc_real P_roll[4], P_pitch[4];  /* [P00, P01, P10, P11] of each axis */
    fc_real gain_roll[2], gain_pitch[2];  /* the last update's gains (diagnostics) */
    fc_estimate last;
    fc_real r_step;  /* this step's measurement variance (R_loop_time) */
    /* derived from params (PaperKalmanFilter._configure) */
    fc_real q_angle, q_bias, r, r_loop, gate_low2, gate_high2;
} fc_paper_kf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_paper_kf);

/* The tilt stage: the steps of one sample, for a filter that drives them (the position filters;
 * PaperKalmanFilter's methods of the same names). */
/* propagate; sc: the sines and cosines of roll and pitch (sin r, cos r, sin p, cos p), or NULL */
void fc_paper_kf_propagate(fc_paper_kf *f, const fc_real prev[3], const fc_real g[3], fc_real dt,
                           const fc_real sc[4]);
int fc_paper_kf_accel_trusted(const fc_paper_kf *f, fc_real norm2);
void fc_paper_kf_correct(fc_paper_kf *f, fc_real ax, fc_real ay, fc_real az);
void fc_paper_kf_correct_innovation(fc_paper_kf *f, fc_real y_roll, fc_real y_pitch);
void fc_paper_kf_correct_bias(fc_paper_kf *f, fc_real z_x, fc_real z_y, fc_real r);
void fc_paper_kf_took_sample(fc_paper_kf *f, const fc_real g[3]);

/* An update's gain rule: K and the new P from P and R (fc_paper_kf_measurement_gain, or the
 * recommended filter's angle-only rule). */
typedef void (*fc_kf_gain_rule)(const fc_real P[4], fc_real r, fc_real K[2], fc_real out[4]);

/* The roll and the pitch filter updated together (papers/kalman.py's RollPitchAxes, shared
 * with the recommended filter, fc_kf.c): their states by pointer. One covariance while
 * P_roll == P_pitch (the same numbers as twice), axis by axis otherwise. */
typedef struct fc_roll_pitch_axes {
    fc_real *roll, *pitch, *bias_x, *bias_y;
    fc_real *P_roll, *P_pitch;         /* [4] each */
    fc_real *gain_roll, *gain_pitch;   /* [2] each */
} fc_roll_pitch_axes;
/* The axes of a filter f whose fields are named as fc_paper_kf's (a compound literal: valid to
 * the end of the enclosing block, never kept in a state) */
#define FC_ROLL_PITCH_AXES(f)                                                                  \
    (&(fc_roll_pitch_axes){&(f)->roll, &(f)->pitch, &(f)->bias_x, &(f)->bias_y, (f)->P_roll,   \
                           (f)->P_pitch, (f)->gain_roll, (f)->gain_pitch})

/* The equations (papers/kalman.py's functions of the same names) and the two axes' steps, inline
 * here: the recommended filter (fc_kf.c) updates its axes with them every sample, and a call
 * through a gain rule's pointer that no compiler can inline cost it 7 % of its time. */
/* predict_covariance: F P F' + Q (Das & Mary eq. 19-22) */
static inline void fc_paper_kf_predict_covariance(const fc_real P[4], fc_real dt, fc_real q_angle,
                                                  fc_real q_bias, fc_real out[4])
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    out[0] = P00 + dt * (dt * P11 - P01 - P10 + q_angle);
    out[1] = P01 - dt * P11;
    out[2] = P10 - dt * P11;
    out[3] = P11 + q_bias * dt;
}

/* measurement_gain (Das & Mary eq. 23-27), with the papers' temporaries */
static inline void fc_paper_kf_measurement_gain(const fc_real P[4], fc_real r, fc_real K[2],
                                                fc_real out[4])
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    fc_real S = P00 + r;
    fc_real K0 = P00 / S, K1 = P10 / S;
    K[0] = K0;
    K[1] = K1;
    out[0] = P00 - K0 * P00;
    out[1] = P01 - K0 * P01;
    out[2] = P10 - K1 * P00;
    out[3] = P11 - K1 * P01;
}

/* bias_update: a direct bias measurement, H = [0, 1] */
static inline void fc_paper_kf_bias_update(fc_real *angle, fc_real *bias, fc_real P[4], fc_real y,
                                           fc_real r)
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    fc_real S = P11 + r;
    fc_real K0 = P01 / S, K1 = P11 / S;
    *angle = *angle + K0 * y;
    *bias = *bias + K1 * y;
    P[0] = P00 - K0 * P10;
    P[1] = P01 - K0 * P11;
    P[2] = P10 - K1 * P10;
    P[3] = P11 - K1 * P11;
}

static inline int fc_same4(const fc_real a[4], const fc_real b[4])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[3] == b[3];
}

/* RollPitchAxes.predict_covariances */
static inline void fc_roll_pitch_predict_covariances(const fc_roll_pitch_axes *a, fc_real dt,
                                                     fc_real q_angle, fc_real q_bias)
{
    fc_real P[4];
    memcpy(P, a->P_roll, sizeof P);
    fc_paper_kf_predict_covariance(P, dt, q_angle, q_bias, a->P_roll);
    if (fc_same4(a->P_pitch, P)) {
        memcpy(a->P_pitch, a->P_roll, sizeof P);
    } else {
        fc_real Pp[4];
        memcpy(Pp, a->P_pitch, sizeof Pp);
        fc_paper_kf_predict_covariance(Pp, dt, q_angle, q_bias, a->P_pitch);
    }
}

/* RollPitchAxes.update_angles */
static inline void fc_roll_pitch_update_angles(const fc_roll_pitch_axes *a, fc_real r,
                                               fc_real y_roll, fc_real y_pitch,
                                               fc_kf_gain_rule gain)
{
    fc_real P[4];
    memcpy(P, a->P_roll, sizeof P);
    int shared = fc_same4(a->P_pitch, P);
    gain(P, r, a->gain_roll, a->P_roll);
    if (shared) {
        memcpy(a->gain_pitch, a->gain_roll, 2 * sizeof *a->gain_roll);
        memcpy(a->P_pitch, a->P_roll, sizeof P);
    } else {
        fc_real Pp[4];
        memcpy(Pp, a->P_pitch, sizeof Pp);
        gain(Pp, r, a->gain_pitch, a->P_pitch);
    }
    fc_real roll = *a->roll + a->gain_roll[0] * y_roll;
    *a->bias_x += a->gain_roll[1] * y_roll;
    fc_real pitch = *a->pitch + a->gain_pitch[0] * y_pitch;
    *a->bias_y += a->gain_pitch[1] * y_pitch;
    *a->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    *a->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
}

/* RollPitchAxes.correct_bias */
static inline void fc_roll_pitch_correct_bias(const fc_roll_pitch_axes *a, fc_real z_x,
                                              fc_real z_y, fc_real r)
{
    fc_paper_kf_bias_update(a->roll, a->bias_x, a->P_roll, z_x - *a->bias_x, r);
    fc_paper_kf_bias_update(a->pitch, a->bias_y, a->P_pitch, z_y - *a->bias_y, r);
}


#endif /* FC_PAPER_KF_H */
